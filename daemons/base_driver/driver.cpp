#include "driver.hpp"

#include <chrono>
#include <utility>
#include <vector>

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
  o.geometry.counts_per_rev = config.get<double>("counts_per_rev", o.geometry.counts_per_rev, in_range(1.0, 1e8));
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

const DriverOptions& validated(const DriverOptions& o) {
  if (std::string e = o.geometry.validate(); !e.empty()) throw runtime::ConfigError(e);
  return o;
}

std::chrono::microseconds period_of(double rate_hz) {
  return std::chrono::microseconds(static_cast<std::int64_t>(1e6 / rate_hz));
}

}  // namespace

Driver::Driver(runtime::Node& node, const DriverOptions& options)
    : node_(node), can_(open_transport(options)), core_(validated(options), outputs()) {
  node_.collect_counters([this]() -> decltype(auto) { return core_.counters(); });
  node_.subscribe<pex::velocity_cmd_t>(runtime::channels::kBaseCmd, [this](const pex::velocity_cmd_t& cmd) {
    core_.on_command(cmd, node_.monotonic_us());  // a refusal (std::invalid_argument): counted by the node
  });
  node_.watch_fd(can_->fd(), [this] { read_frames(); });
  node_.every(period_of(options.control_rate_hz), [this](std::int64_t) {
    read_frames();
    core_.control(node_.monotonic_us());
  });
  node_.every(period_of(options.odometry_rate_hz), [this](std::int64_t) {
    core_.publish_odometry(node_.monotonic_us());
  });
  node_.set_state(pex::daemon_status_t::STATE_DEGRADED, "waiting for the drives on " + can_->describe());
  spdlog::info("CAN {} nodes {} and {}, {:.1f} counts/m, cmd timeout {} ms", can_->describe(), options.left_node_id,
               options.right_node_id, options.geometry.counts_per_m(), options.cmd_timeout_ms);
}

DriverOutputs Driver::outputs() {
  DriverOutputs out;
  out.send_frame = [this](const canopen::Frame& frame, std::string* error) { return can_->send(frame, error); };
  out.publish_odometry = [this](const pex::odometry_t& msg) { node_.publish(runtime::channels::kOdometry, msg); };
  out.report = [this](const runtime::DaemonHealth& health) {
    node_.set_state(health.state, health.reason);
  };
  out.error = [this](std::string_view key, const std::string& text) { node_.error(key, text); };
  out.reject = [this](std::string_view key, const std::string& text) { node_.reject(key, text); };
  return out;
}

void Driver::read_frames() {
  if (!node_.clock_started()) {
    // clock = "sim" before the first SIM_CLOCK: a frame cannot be timed, and
    // one timed 0 would read as a heartbeat lost when the clock starts. The
    // drives repeat their heartbeats; drop these.
    while (can_->receive()) ++node_.counter("can_frames_before_clock");
    return;
  }
  // Heartbeat, SDO and velocity timing on the monotonic clock; the odometry
  // stamp (ODOMETRY utime) on the stamping clock.
  std::vector<canopen::Frame> frames;
  while (auto frame = can_->receive()) frames.push_back(*frame);
  core_.on_frames(frames, node_.monotonic_us(), node_.now_utime());
  node_.counter("can_malformed_datagrams") = static_cast<std::int64_t>(can_->malformed());
}

}  // namespace pex::base_driver
