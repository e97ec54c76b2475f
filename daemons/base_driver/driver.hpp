#pragma once
// pex-base-driver's shell: options from config/base_driver.toml, and the
// driver, which wires a DriverCore (driver_core.hpp: all the logic) to the
// node (BASE_CMD, timers, ODOMETRY, DAEMON_STATUS) and the CAN transport.
#include <memory>

#include "driver_core.hpp"
#include "hwio/hwio.hpp"
#include "runtime/config.hpp"

namespace pex::runtime {
class Node;
}

namespace pex::base_driver {

DriverOptions load_options(runtime::ConfigReader& config);

class Driver {
 public:
  // Opens the transport (throws runtime::Unavailable) and checks the geometry
  // (throws runtime::ConfigError).
  Driver(runtime::Node& node, const DriverOptions& options);

 private:
  DriverOutputs outputs();
  // Hands every frame waiting on the transport to the core.
  void read_frames();
  // The core's counters into DAEMON_STATUS.

  runtime::Node& node_;
  std::unique_ptr<hwio::FrameTransport> can_;
  DriverCore core_;
};

}  // namespace pex::base_driver
