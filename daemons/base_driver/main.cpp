// pex-base-driver: BASE_CMD -> CiA 402 wheel drives on CAN; encoders -> ODOMETRY.
// Stops the wheels on stale commands, node faults, lost heartbeats and CAN
// error frames, and reports why in DAEMON_STATUS.
#include <memory>

#include "driver.hpp"
#include "runtime/daemon.hpp"

int main(int argc, char** argv) {
  std::unique_ptr<pex::base_driver::Driver> driver;
  return pex::runtime::run_daemon(argc, argv, {.name = "base_driver",
                                   .description = "differential base over CANopen CiA 402 -> ODOMETRY",
                                   .load_options = [](auto& c) { (void)pex::base_driver::load_options(c); }},
                                  [&driver](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
                                    driver = std::make_unique<pex::base_driver::Driver>(
                                        node, pex::base_driver::load_options(config));
                                  });
}
