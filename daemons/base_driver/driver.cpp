#include "driver.hpp"

#include <chrono>
#include <cmath>

#include <linux/can/error.h>
#include <pex/daemon_status_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/velocity_cmd_t.hpp>
#include <spdlog/spdlog.h>

#include "runtime/channels.hpp"
#include "runtime/daemon.hpp"
#include "runtime/node.hpp"

namespace pex::base_driver {

using runtime::in_range;
using runtime::one_of;
using runtime::positive;

DriverOptions load_options(runtime::ConfigReader& config) {
  DriverOptions o;
  o.can_transport = config.get<std::string>("can_transport", o.can_transport, one_of({"socketcan", "local"}));
  o.can_interface = config.get<std::string>("can_interface", o.can_interface);
  o.can_local_path = config.get<std::string>("can_local_path", o.can_local_path);
  o.left_node_id = static_cast<std::uint8_t>(config.get<int>("left_node_id", o.left_node_id, in_range(1, 127)));
  o.right_node_id = static_cast<std::uint8_t>(config.get<int>("right_node_id", o.right_node_id, in_range(1, 127)));
  if (o.left_node_id == o.right_node_id) throw runtime::ConfigError(config.origin() + ": node ids must differ");
  o.geometry.counts_per_rev = config.get<double>("counts_per_rev", o.geometry.counts_per_rev, positive<double>());
  o.geometry.gear_ratio = config.get<double>("gear_ratio", o.geometry.gear_ratio, positive<double>());
  o.geometry.wheel_radius_m = config.get<double>("wheel_radius_m", o.geometry.wheel_radius_m, in_range(0.01, 2.0));
  o.geometry.wheel_base_m = config.get<double>("wheel_base_m", o.geometry.wheel_base_m, in_range(0.05, 5.0));
  o.limits.max_speed_mps = config.get<double>("max_speed_mps", o.limits.max_speed_mps, in_range(0.01, 10.0));
  o.limits.max_omega_radps = config.get<double>("max_omega_radps", o.limits.max_omega_radps, in_range(0.01, 20.0));
  o.limits.max_wheel_speed_mps =
      config.get<double>("max_wheel_speed_mps", o.limits.max_wheel_speed_mps, in_range(0.01, 10.0));
  o.limits.max_wheel_accel_mps2 =
      config.get<double>("max_wheel_accel_mps2", o.limits.max_wheel_accel_mps2, in_range(0.01, 50.0));
  o.odometry.sigma_translation_per_sqrt_m = config.get<double>(
      "odometry_sigma_translation_per_sqrt_m", o.odometry.sigma_translation_per_sqrt_m, in_range(0.0, 1.0));
  o.odometry.sigma_rotation_per_sqrt_rad = config.get<double>(
      "odometry_sigma_rotation_per_sqrt_rad", o.odometry.sigma_rotation_per_sqrt_rad, in_range(0.0, 1.0));
  o.odometry.sigma_rotation_per_sqrt_m = config.get<double>(
      "odometry_sigma_rotation_per_sqrt_m", o.odometry.sigma_rotation_per_sqrt_m, in_range(0.0, 1.0));
  o.cmd_timeout_ms = config.get<int>("cmd_timeout_ms", o.cmd_timeout_ms, in_range(10, 10'000));
  o.control_rate_hz = config.get<double>("control_rate_hz", o.control_rate_hz, in_range(10.0, 1000.0));
  o.odometry_rate_hz = config.get<double>("odometry_rate_hz", o.odometry_rate_hz, in_range(1.0, 1000.0));
  o.heartbeat_timeout_ms = config.get<int>("heartbeat_timeout_ms", o.heartbeat_timeout_ms, in_range(20, 60'000));
  o.sdo_timeout_ms = config.get<int>("sdo_timeout_ms", o.sdo_timeout_ms, in_range(10, 60'000));
  o.error_frame_hold_ms = config.get<int>("error_frame_hold_ms", o.error_frame_hold_ms, in_range(0, 60'000));
  o.master_node_id = config.get<int>("master_node_id", o.master_node_id, in_range(1, 127));
  if (o.master_node_id == o.left_node_id || o.master_node_id == o.right_node_id)
    config.fail("master_node_id", "must differ from the drives' node ids");
  o.master_heartbeat_period_ms =
      config.get<int>("master_heartbeat_period_ms", o.master_heartbeat_period_ms, in_range(10, 10'000));
  o.drive_heartbeat_consumer_ms =
      config.get<int>("drive_heartbeat_consumer_ms", o.drive_heartbeat_consumer_ms, in_range(0, 60'000));
  // CiA 301: the consumer time must exceed the producer period, or every
  // heartbeat is late; twice the period leaves room for one lost frame.
  if (o.drive_heartbeat_consumer_ms > 0 && o.drive_heartbeat_consumer_ms < 2 * o.master_heartbeat_period_ms)
    config.fail("drive_heartbeat_consumer_ms", "must be 0 (off) or at least twice master_heartbeat_period_ms");
  o.drive_abort_option = config.get<std::string>("drive_abort_option", o.drive_abort_option,
                                                 one_of({"quick_stop", "fault", "disable_voltage"}));
  o.quick_stop_decel_mps2 =
      config.get<double>("quick_stop_decel_mps2", o.quick_stop_decel_mps2, in_range(0.1, 50.0));
  return o;
}

namespace {

std::unique_ptr<hwio::FrameTransport> open_transport(const DriverOptions& o) {
  auto transport =
      o.can_transport == "local"
          ? hwio::connect_local_bus(o.can_local_path)
          : hwio::open_socketcan(hwio::SocketCanOptions{o.can_interface, {}, /*error_frames=*/true});
  // Fail fast at start with the one clear line (exit 69 for systemd).
  if (!transport) throw runtime::Unavailable(transport.error());
  return std::move(*transport);
}

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

}  // namespace

Driver::Driver(runtime::Node& node, DriverOptions options)
    : node_(node),
      options_(std::move(options)),
      can_(open_transport(options_)),
      master_(master_options(options_)),
      limiter_(options_.geometry, options_.limits),
      odometry_(options_.geometry, options_.odometry) {
  if (std::string e = options_.geometry.validate(); !e.empty()) throw runtime::ConfigError(e);
  node_.subscribe<pex::velocity_cmd_t>(runtime::channels::kBaseCmd,
                                       [this](const pex::velocity_cmd_t& cmd) { on_command(cmd); });
  node_.watch_fd(can_->fd(), [this] { on_frames(); });
  node_.every(std::chrono::microseconds(static_cast<std::int64_t>(1e6 / options_.control_rate_hz)),
              [this](std::int64_t) { control(node_.monotonic_us()); });
  node_.every(std::chrono::microseconds(static_cast<std::int64_t>(1e6 / options_.odometry_rate_hz)),
              [this](std::int64_t) { publish_odometry(node_.monotonic_us()); });
  node_.set_state(pex::daemon_status_t::STATE_DEGRADED, "waiting for the drives on " + can_->describe());
  spdlog::info("CAN {} nodes {} and {}, {:.1f} counts/m, cmd timeout {} ms", can_->describe(),
               options_.left_node_id, options_.right_node_id, options_.geometry.counts_per_m(),
               options_.cmd_timeout_ms);
}

void Driver::on_command(const pex::velocity_cmd_t& cmd) {
  if (!std::isfinite(cmd.v) || !std::isfinite(cmd.omega)) {
    throw runtime::BadInput("BASE_CMD with a non-finite velocity from '" + cmd.source + "'");
  }
  command_ = kinematics::BodyVelocity{cmd.v, cmd.omega};
  command_us_ = node_.monotonic_us();
  ++node_.counter("commands");
}

void Driver::on_frames() {
  if (!node_.clock_started()) {
    // clock = "sim" before the first SIM_CLOCK: a frame cannot be timed, and
    // one timed 0 would read as a heartbeat lost when the clock starts. The
    // drives repeat their heartbeats; drop these.
    while (can_->receive()) ++node_.counter("can_frames_before_clock");
    return;
  }
  // Heartbeat, SDO and velocity timing on the monotonic clock; the odometry
  // stamp (ODOMETRY utime) on the stamping clock.
  const std::int64_t now_us = node_.monotonic_us();
  while (auto frame = can_->receive()) {
    if (frame->can_id & CAN_ERR_FLAG) {
      // A bus error (bus-off, error passive, lost arbitration, ...): stop and hold.
      ++node_.counter("can_error_frames");
      last_error_frame_us_ = now_us;
      node_.error("can", "CAN error frame, class 0x" + [&] {
        char b[16];
        std::snprintf(b, sizeof b, "%X", frame->can_id & CAN_ERR_MASK);
        return std::string(b);
      }());
      continue;
    }
    master_.handle(*frame, now_us);
  }
  node_.counter("can_malformed_datagrams") = static_cast<std::int64_t>(can_->malformed());
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
    positions_utime_ = node_.now_utime();
    const std::uint64_t rejected = odometry_.rejected_jumps();
    odometry_.update(nodes[0].position_actual, nodes[1].position_actual, now_us);
    if (odometry_.rejected_jumps() != rejected) node_.reject("encoder", "implausible encoder jump: re-baselined");
  }
}

void Driver::control(std::int64_t now_us) {
  on_frames();
  const double dt = last_control_us_ ? (now_us - last_control_us_) * 1e-6 : 0.0;
  last_control_us_ = now_us;
  const bool stale = command_us_ == 0 || now_us - command_us_ > 1000ll * options_.cmd_timeout_ms;
  if (stale && !cmd_timed_out_ && command_us_ != 0) ++node_.counter("cmd_timeouts");
  cmd_timed_out_ = stale;
  const bool error_recent = last_error_frame_us_ != 0 && now_us - last_error_frame_us_ < 1000ll * options_.error_frame_hold_ms;
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
    if (!can_->send(frame, &error)) {
      ++node_.counter("can_send_errors");
      node_.error("can_send", error);
    }
  }
  report(now_us, stale, error_recent);
}

void Driver::publish_odometry(std::int64_t now_us) {
  const auto& s = odometry_.state();
  pex::odometry_t msg{};
  const auto& nodes = master_.nodes();
  const std::int64_t newest_us = std::max(nodes[0].position_time_us, nodes[1].position_time_us);
  if (positions_utime_ == 0) return;  // no encoder reading yet
  // Encoder readings older than the heartbeat timeout mean the drives are
  // gone: publish nothing rather than a stale pose with a fresh look.
  if (now_us - newest_us > 1000ll * options_.heartbeat_timeout_ms) {
    ++node_.counter("odometry_withheld");
    return;
  }
  msg.utime = positions_utime_;
  msg.x = s.pose.x_m;
  msg.y = s.pose.y_m;
  msg.theta = s.pose.theta_rad;
  msg.v = s.v_mps;
  msg.omega = s.omega_radps;
  for (int i = 0; i < 9; ++i) msg.covariance[i] = s.covariance[static_cast<std::size_t>(i)];
  node_.publish(runtime::channels::kOdometry, msg);
}

void Driver::report(std::int64_t, bool cmd_stale, bool error_recent) {
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
      problem = "node " + std::to_string(n.node_id) + ": fault (EMCY 0x" + [&] {
        char b[8];
        std::snprintf(b, sizeof b, "%04X", n.last_emcy_code);
        return std::string(b);
      }() + ")";
    } else if (n.phase != canopen::Cia402Master::Phase::kReady) {
      problem = "node " + std::to_string(n.node_id) + ": " + canopen::to_string(n.phase);
    }
  }
  node_.counter("node_faults") = faults;
  node_.counter("heartbeat_losses") = losses;
  node_.counter("emcy_frames") = emcy;
  node_.counter("node_restarts") = restarts;
  node_.counter("can_frames_malformed") = static_cast<std::int64_t>(master_.counters().frames_malformed);
  node_.counter("sdo_aborts") = static_cast<std::int64_t>(master_.counters().sdo_aborts);
  node_.counter("odometry_jumps") = static_cast<std::int64_t>(odometry_.rejected_jumps());
  node_.counter("stopped") = safe_stop_ ? 1 : 0;
  if (error_recent) {
    node_.set_state(pex::daemon_status_t::STATE_ERROR, "CAN error frame: wheels stopped");
  } else if (!problem.empty()) {
    node_.set_state(pex::daemon_status_t::STATE_ERROR, problem + ": wheels stopped");
  } else if (cmd_stale) {
    node_.set_state(pex::daemon_status_t::STATE_OK, "no BASE_CMD: wheels held at zero");
  } else {
    node_.set_state(pex::daemon_status_t::STATE_OK);
  }
}

}  // namespace pex::base_driver
