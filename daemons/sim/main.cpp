// pex-sim: the world, the robot and its devices. Serves the LMS111's CoLa-A
// protocol on a loopback TCP port, plays the CiA 402 wheel drives on the CAN
// transport, publishes the ground truth on SIM_TRUTH (for evaluation only) and
// its clock on SIM_CLOCK, which daemons with clock = "sim" run on.
#include <memory>
#include <optional>
#include <string>

#include "runtime/daemon.hpp"
#include "simulator.hpp"

int main(int argc, char** argv) {
  std::optional<double> speed;
  std::string world;
  std::unique_ptr<pex::simd::Simulator> simulator;  // outlives the node's handlers' use of it
  pex::runtime::DaemonInfo info{"sim", "simulated world, LMS111 (CoLa-A/TCP) and CiA 402 wheel drives (CAN)"};
  info.is_clock_source = true;  // publishes SIM_CLOCK, paced by the wall clock x speed
  info.load_options = [](auto& c) { (void)pex::simd::load_options(c); };
  info.add_options = [&speed, &world](CLI::App& app) {
    app.add_option_function<double>(
           "--speed", [&speed](double factor) { speed = factor; },
           "simulated seconds per wall-clock second (overrides speed_factor)")
        ->check(CLI::Range(0.01, 100.0));
    app.add_option("--world", world, "world file (WKT, see worlds/; overrides world_file)")
        ->check(CLI::ExistingFile);
  };
  return pex::runtime::run_daemon(argc, argv, info,
                                  [&](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
                                    auto options = pex::simd::load_options(config);
                                    if (speed) options.speed_factor = *speed;
                                    if (!world.empty()) options.world_file = world;
                                    simulator = std::make_unique<pex::simd::Simulator>(node, std::move(options));
                                  });
}
