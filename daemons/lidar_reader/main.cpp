// pex-lidar-reader: SICK LMS1xx over CoLa-A/TCP -> LIDAR_SCAN. Connects with a
// timeout, logs in and configures as the telegram listing says, streams
// sSN LMDscandata, and reconnects with exponential back-off.
#include <memory>

#include "reader.hpp"
#include "runtime/daemon.hpp"

int main(int argc, char** argv) {
  std::unique_ptr<pex::lidar_reader::Reader> reader;
  return pex::runtime::run_daemon(argc, argv, {.name = "lidar_reader",
                                   .description = "SICK LMS1xx (CoLa-A over TCP) -> LIDAR_SCAN",
                                   .load_options = [](auto& c) { (void)pex::lidar_reader::load_options(c); }},
                                  [&reader](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
                                    reader = std::make_unique<pex::lidar_reader::Reader>(
                                        node, pex::lidar_reader::load_options(config));
                                  });
}
