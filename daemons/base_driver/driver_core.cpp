#include "driver_core.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <cstdio>

#include <linux/can/error.h>
#include <pex/daemon_status_t.hpp>

namespace pex::base_driver {

namespace {

canopen::Cia402Master::Options master_options(const DriverOptions& o) {
  canopen::Cia402Master::Options m;
  m.node_ids = {o.left_node_id, o.right_node_id};
  m.heartbeat_timeout_us = 1000ll * o.heartbeat_timeout_ms;
  m.sdo_timeout_us = 1000ll * o.sdo_timeout_ms;
  m.master_node_id = static_cast<std::uint8_t>(o.master_node_id);
  m.master_heartbeat_period_us = 1000ll * o.master_heartbeat_period_ms;
  m.drive_heartbeat_consumer_us = 1000ll * o.drive_heartbeat_consumer_ms;
  m.abort_option = o.drive_abort_option == "fault"             ? canopen::AbortConnectionOption::kFault
                   : o.drive_abort_option == "disable_voltage" ? canopen::AbortConnectionOption::kDisableVoltage
                                                               : canopen::AbortConnectionOption::kQuickStop;
  m.quick_stop_deceleration =
      static_cast<std::uint32_t>(std::lround(o.quick_stop_decel_mps2 * o.geometry.counts_per_m()));
  return m;
}

std::string hex_text(const char* format, unsigned value) {
  char b[16];
  std::snprintf(b, sizeof b, format, value);
  return b;
}

}  // namespace

DriverCore::DriverCore(const DriverOptions& options, DriverOutputs outputs)
    : options_(options),
      outputs_(std::move(outputs)),
      master_(master_options(options_)),
      limiter_(options_.geometry, options_.limits),
      odometry_(options_.geometry, options_.odometry) {}

void DriverCore::on_command(const pex::velocity_cmd_t& cmd, std::int64_t now_us) {
  if (!std::isfinite(cmd.v) || !std::isfinite(cmd.omega))
    throw std::invalid_argument("BASE_CMD with a non-finite velocity from '" + cmd.source + "'");
  // A command over the limits is clipped by the limiter (a planner may ask
  // for "as fast as allowed"), and counted; one far beyond them is no command
  // a sane sender makes: refused, the command in force kept.
  const double max_v = options_.limits.max_speed_mps, max_omega = options_.limits.max_omega_radps;
  if (std::abs(cmd.v) > kAbsurdFactor * max_v || std::abs(cmd.omega) > kAbsurdFactor * max_omega) {
    throw std::invalid_argument("BASE_CMD v = " + std::to_string(cmd.v) + " m/s, omega = " + std::to_string(cmd.omega) +
                                " rad/s from '" + cmd.source + "': more than " +
                                std::to_string(static_cast<int>(kAbsurdFactor)) + " x the limits");
  }
  if (std::abs(cmd.v) > max_v || std::abs(cmd.omega) > max_omega) ++counters_.commands_clipped;
  command_ = kinematics::BodyVelocity{cmd.v, cmd.omega};
  command_us_ = now_us;
  ++counters_.commands;
}

void DriverCore::on_frames(const std::vector<canopen::Frame>& frames, std::int64_t now_us, std::int64_t now_utime) {
  for (const auto& frame : frames) {
    if (frame.can_id & CAN_ERR_FLAG) {
      // A bus error (bus-off, error passive, lost arbitration, ...): stop and hold.
      ++counters_.can_error_frames;
      last_error_frame_us_ = now_us;
      outputs_.error("can", "CAN error frame, class 0x" + hex_text("%X", frame.can_id & CAN_ERR_MASK));
      continue;
    }
    master_.handle(frame, now_us);
  }
  // New encoder readings from both wheels -> odometry.
  const auto& nodes = master_.nodes();
  for (int i = 0; i < 2; ++i) {
    if (nodes[static_cast<std::size_t>(i)].restarts != restarts_seen_[i]) {
      restarts_seen_[i] = nodes[static_cast<std::size_t>(i)].restarts;
      odometry_.rebaseline();  // its counter restarted from zero
    }
  }
  if (nodes[0].position_seen && nodes[1].position_seen && nodes[0].position_time_us != last_positions_us_[0] &&
      nodes[1].position_time_us != last_positions_us_[1]) {
    last_positions_us_[0] = nodes[0].position_time_us;
    last_positions_us_[1] = nodes[1].position_time_us;
    positions_utime_ = now_utime;
    const std::uint64_t rejected = odometry_.rejected_jumps();
    odometry_.update(nodes[0].position_actual, nodes[1].position_actual, now_us);
    if (odometry_.rejected_jumps() != rejected) outputs_.reject("encoder", "implausible encoder jump: re-baselined");
  }
}

void DriverCore::control(std::int64_t now_us) {
  const double dt = last_control_us_ ? (now_us - last_control_us_) * 1e-6 : 0.0;
  last_control_us_ = now_us;
  const bool stale = command_us_ == 0 || now_us - command_us_ > 1000ll * options_.cmd_timeout_ms;
  if (stale && !cmd_timed_out_ && command_us_ != 0) ++counters_.cmd_timeouts;
  cmd_timed_out_ = stale;
  const bool error_recent =
      last_error_frame_us_ != 0 && now_us - last_error_frame_us_ < 1000ll * options_.error_frame_hold_ms;
  const bool drives_ok = master_.all_ready();
  safe_stop_ = stale || error_recent || !drives_ok;
  if (!drives_ok || error_recent) limiter_.reset();  // restart from standstill when they come back
  const kinematics::WheelSpeeds wheels = limiter_.step(safe_stop_ ? kinematics::BodyVelocity{} : command_, dt);
  const double per_m = options_.geometry.counts_per_m();
  std::vector<std::int32_t> targets = {static_cast<std::int32_t>(std::lround(wheels.left_mps * per_m)),
                                       static_cast<std::int32_t>(std::lround(wheels.right_mps * per_m))};
  if (!drives_ok || error_recent) targets = {0, 0};
  for (const auto& frame : master_.step(now_us, targets)) {
    std::string error;
    if (!outputs_.send_frame(frame, &error)) {
      ++counters_.can_send_errors;
      outputs_.error("can_send", error);
    }
  }
  report(stale, error_recent);
}

void DriverCore::publish_odometry(std::int64_t now_us) {
  const auto& s = odometry_.state();
  pex::odometry_t msg{};
  const auto& nodes = master_.nodes();
  const std::int64_t newest_us = std::max(nodes[0].position_time_us, nodes[1].position_time_us);
  if (positions_utime_ == 0) return;  // no encoder reading yet
  // Encoder readings older than the heartbeat timeout mean the drives are
  // gone: publish nothing rather than a stale pose with a fresh look.
  if (now_us - newest_us > 1000ll * options_.heartbeat_timeout_ms) {
    ++counters_.odometry_withheld;
    return;
  }
  msg.utime = positions_utime_;
  msg.x = s.pose.x_m;
  msg.y = s.pose.y_m;
  msg.theta = s.pose.theta_rad;
  msg.v = s.v_mps;
  msg.omega = s.omega_radps;
  for (int i = 0; i < 9; ++i) msg.covariance[i] = s.covariance[static_cast<std::size_t>(i)];
  outputs_.publish_odometry(msg);
}

void DriverCore::report(bool cmd_stale, bool error_recent) {
  const auto& nodes = master_.nodes();
  std::int64_t faults = 0, losses = 0, emcy = 0, restarts = 0;
  std::string problem;
  for (const auto& n : nodes) {
    faults += static_cast<std::int64_t>(n.faults);
    losses += static_cast<std::int64_t>(n.heartbeat_losses);
    emcy += static_cast<std::int64_t>(n.emcy_count);
    restarts += static_cast<std::int64_t>(n.restarts);
    if (!problem.empty()) continue;
    if (n.heartbeat_lost) {
      problem = "node " + std::to_string(n.node_id) + ": no heartbeat";
    } else if (n.statusword_seen && n.drive_state == canopen::DriveState::kFault) {
      problem = "node " + std::to_string(n.node_id) + ": fault (EMCY 0x" + hex_text("%04X", n.last_emcy_code) + ")";
    } else if (n.phase != canopen::Cia402Master::Phase::kReady) {
      problem = "node " + std::to_string(n.node_id) + ": " + canopen::to_string(n.phase);
    }
  }
  counters_.node_faults = faults;
  counters_.heartbeat_losses = losses;
  counters_.emcy_frames = emcy;
  counters_.node_restarts = restarts;
  counters_.can_frames_malformed = static_cast<std::int64_t>(master_.counters().frames_malformed);
  counters_.sdo_aborts = static_cast<std::int64_t>(master_.counters().sdo_aborts);
  counters_.odometry_jumps = static_cast<std::int64_t>(odometry_.rejected_jumps());
  counters_.stopped = safe_stop_ ? 1 : 0;
  runtime::DaemonHealth health;
  if (error_recent) {
    health = {pex::daemon_status_t::STATE_ERROR, "CAN error frame: wheels stopped"};
  } else if (!problem.empty()) {
    health = {pex::daemon_status_t::STATE_ERROR, problem + ": wheels stopped"};
  } else if (cmd_stale) {
    health = {pex::daemon_status_t::STATE_OK, "no BASE_CMD: wheels held at zero"};
  } else {
    health = {pex::daemon_status_t::STATE_OK, ""};
  }
  outputs_.report(health);
}

}  // namespace pex::base_driver
