#pragma once
// pex-base-driver's logic without a bus, a node or a clock: BASE_CMD, the
// frames read from the CAN bus and the time in; frames to send, ODOMETRY and
// health out, through DriverOutputs. The daemon's shell (driver.hpp) feeds it
// from its node's subscription, timers and the transport's descriptor; the
// tests feed it frames of simulated drives (canopen::DriveNode).
//
// Times: `now_us` is a monotonic clock (timeouts, rates; any epoch, never
// going back), `now_utime` the stamping clock (ODOMETRY.utime).
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <pex/odometry_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include "runtime/daemon_state.hpp"
#include "canopen/canopen.hpp"
#include "kinematics/kinematics.hpp"

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

// What DAEMON_STATUS counts under these names (docs/can.md).
struct DriverCounters {
  // Events, counted as they happen.
  std::int64_t commands = 0;           // BASE_CMD taken
  std::int64_t commands_clipped = 0;   // taken, but over max_speed_mps / max_omega_radps (the limiter clips them)
  std::int64_t cmd_timeouts = 0;       // times the command went stale
  std::int64_t can_error_frames = 0;
  std::int64_t can_send_errors = 0;
  std::int64_t odometry_withheld = 0;  // ODOMETRY periods without a fresh encoder reading
  // Totals of the drives and the odometry, as of the last control step.
  std::int64_t node_faults = 0;
  std::int64_t heartbeat_losses = 0;
  std::int64_t emcy_frames = 0;
  std::int64_t node_restarts = 0;
  std::int64_t can_frames_malformed = 0;  // ours, but wrong length or flags
  std::int64_t sdo_aborts = 0;
  std::int64_t odometry_jumps = 0;
  std::int64_t stopped = 1;            // 1 while the wheels are held at zero

  // By name, for DAEMON_STATUS (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    v.event("commands", commands);
    v.event("commands_clipped", commands_clipped);
    v.event("cmd_timeouts", cmd_timeouts);
    v.event("can_error_frames", can_error_frames);
    v.event("can_send_errors", can_send_errors);
    v.event("odometry_withheld", odometry_withheld);
    v.total("node_faults", node_faults);
    v.total("heartbeat_losses", heartbeat_losses);
    v.total("emcy_frames", emcy_frames);
    v.total("node_restarts", node_restarts);
    v.total("can_frames_malformed", can_frames_malformed);
    v.total("sdo_aborts", sdo_aborts);
    v.total("odometry_jumps", odometry_jumps);
    v.total("stopped", stopped);
  }
};

struct DriverOutputs {
  // Puts a frame on the bus; false, with the reason in *error, when it could not.
  std::function<bool(const canopen::Frame& frame, std::string* error)> send_frame;
  std::function<void(const pex::odometry_t& msg)> publish_odometry;
  // After every control step, with counters() current.
  std::function<void(const runtime::DaemonHealth& health)> report;
  // An error of the bus or of ours, and input that was refused: `key` groups
  // them for rate-limited logging.
  std::function<void(std::string_view key, const std::string& text)> error;
  std::function<void(std::string_view key, const std::string& text)> reject;
};

// BASE_CMD -> limited wheel velocities -> RPDO1 of the drives; encoder TPDOs
// -> odometry. The wheels are commanded to zero while the command is stale,
// a drive is not ready (fault, lost heartbeat, restarting, stopped by NMT)
// or a CAN error frame came within error_frame_hold_ms.
class DriverCore {
 public:
  // A command beyond this many times max_speed_mps or max_omega_radps is refused.
  static constexpr double kAbsurdFactor = 10.0;
  // The options must be valid (load_options, geometry.validate()).
  DriverCore(const DriverOptions& options, DriverOutputs outputs);

  // A BASE_CMD. One refused (non-finite, or far beyond the limits) throws
  // std::invalid_argument with the reason; the command in force is kept.
  void on_command(const pex::velocity_cmd_t& cmd, std::int64_t now_us);
  // The frames one read of the bus gave, in order, error frames (CAN_ERR_FLAG)
  // included. A pair of fresh encoder readings becomes odometry stamped now_utime.
  void on_frames(const std::vector<canopen::Frame>& frames, std::int64_t now_us, std::int64_t now_utime);
  // One control period: SYNC, RPDO1s, our heartbeat and the master's
  // configuration frames go to send_frame; then report().
  void control(std::int64_t now_us);
  // One odometry period: ODOMETRY to publish_odometry, unless there is no
  // encoder reading yet or the newest is older than heartbeat_timeout_ms.
  void publish_odometry(std::int64_t now_us);

  const DriverOptions& options() const { return options_; }
  const DriverCounters& counters() const { return counters_; }
  const canopen::Cia402Master& master() const { return master_; }

 private:
  void report(bool cmd_stale, bool error_frames_recent);

  DriverOptions options_;
  DriverOutputs outputs_;
  canopen::Cia402Master master_;
  kinematics::VelocityLimiter limiter_;
  kinematics::OdometryIntegrator odometry_;
  kinematics::BodyVelocity command_;
  DriverCounters counters_;
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
