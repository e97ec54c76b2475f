#pragma once
// pex-base-driver's parts: options from config/base_driver.toml and the
// driver (BASE_CMD -> CiA 402 wheel velocities, encoders -> ODOMETRY, safety).
#include <cstdint>
#include <memory>
#include <string>

#include "canopen/canopen.hpp"
#include "hwio/hwio.hpp"
#include "kinematics/kinematics.hpp"
#include "runtime/config.hpp"

namespace pex {
struct velocity_cmd_t;
}
namespace pex::runtime {
class Node;
}

namespace pex::base_driver {

struct DriverOptions {
  std::string can_transport = "socketcan";   // "socketcan" (robot) | "local" (simulator, tests)
  std::string can_interface = "can0";
  std::string can_local_path = "@pex-can";
  std::uint8_t left_node_id = 1;
  std::uint8_t right_node_id = 2;
  kinematics::DriveGeometry geometry;
  kinematics::VelocityLimiter::Options limits;
  kinematics::OdometryIntegrator::Options odometry;
  int cmd_timeout_ms = 250;          // no BASE_CMD for this long -> wheels to zero
  double control_rate_hz = 100.0;    // SYNC + RPDO rate
  double odometry_rate_hz = 50.0;    // ODOMETRY publication rate
  int heartbeat_timeout_ms = 300;    // a node silent this long is lost
  int sdo_timeout_ms = 200;
  int error_frame_hold_ms = 500;     // stop this long after a CAN error frame
  // The drive-side watchdog (canopen.hpp, Cia402Master): our heartbeat every
  // master_heartbeat_period_ms; each drive reacts (drive_abort_option) when it
  // misses it for drive_heartbeat_consumer_ms, so the wheels stop whatever
  // becomes of this daemon.
  int master_node_id = 127;
  int master_heartbeat_period_ms = 50;
  int drive_heartbeat_consumer_ms = 150;  // 0: no drive watchdog
  std::string drive_abort_option = "quick_stop";  // "quick_stop" | "fault" | "disable_voltage"
  double quick_stop_decel_mps2 = 3.0;     // the drives' quick stop ramp, at the wheel
};

DriverOptions load_options(runtime::ConfigReader& config);

class Driver {
 public:
  Driver(runtime::Node& node, DriverOptions options);

 private:
  void on_command(const pex::velocity_cmd_t& cmd);
  void on_frames();
  void control(std::int64_t now_us);
  void publish_odometry(std::int64_t now_us);
  void report(std::int64_t now_us, bool cmd_stale, bool error_frames_recent);

  runtime::Node& node_;
  DriverOptions options_;
  std::unique_ptr<hwio::FrameTransport> can_;
  canopen::Cia402Master master_;
  kinematics::VelocityLimiter limiter_;
  kinematics::OdometryIntegrator odometry_;
  kinematics::BodyVelocity command_;
  // *_us: the node's monotonic clock (timeouts); *_utime: its stamping clock.
  std::int64_t command_us_ = 0;          // when the last BASE_CMD came (0 = never)
  std::int64_t last_control_us_ = 0;
  std::int64_t last_error_frame_us_ = 0;
  std::int64_t last_positions_us_[2] = {0, 0};
  std::int64_t positions_utime_ = 0;     // stamp of the newest pair of encoder readings (0 = none)
  std::uint64_t restarts_seen_[2] = {0, 0};
  bool cmd_timed_out_ = true;
  bool safe_stop_ = true;
};

}  // namespace pex::base_driver
