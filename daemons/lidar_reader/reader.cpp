#include "reader.hpp"

#include <chrono>
#include <optional>
#include <string>
#include <utility>

#include <pex/daemon_status_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <spdlog/spdlog.h>

#include "runtime/channels.hpp"
#include "runtime/node.hpp"

namespace pex::lidar_reader {

using runtime::in_range;

ReaderOptions load_options(runtime::ConfigReader& config) {
  ReaderOptions o;
  o.host = config.get<std::string>("host", o.host, [](const std::string& h) -> std::optional<std::string> {
    // An empty host would be retried for ever as a connection failure.
    if (h.empty() || h.find_first_of(" \t\n") != std::string::npos) return "must be a host name or an IP address";
    return std::nullopt;
  });
  o.port = config.get<int>("port", o.port, in_range(1, 65535));
  o.connect_timeout_ms = config.get<int>("connect_timeout_ms", o.connect_timeout_ms, in_range(10, 60'000));
  o.reply_timeout_ms = config.get<int>("reply_timeout_ms", o.reply_timeout_ms, in_range(10, 60'000));
  o.stale_timeout_ms = config.get<int>("stale_timeout_ms", o.stale_timeout_ms, in_range(100, 60'000));
  o.reconnect_initial_ms = config.get<int>("reconnect_initial_ms", o.reconnect_initial_ms, in_range(10, 60'000));
  o.reconnect_max_ms = config.get<int>("reconnect_max_ms", o.reconnect_max_ms, in_range(10, 600'000));
  if (o.reconnect_max_ms < o.reconnect_initial_ms) {
    throw runtime::ConfigError(config.origin() + ": reconnect_max_ms must be >= reconnect_initial_ms");
  }
  o.configure_scan = config.get<bool>("configure_scan", o.configure_scan);
  o.scan_frequency_hz = config.get<double>("scan_frequency_hz", o.scan_frequency_hz, in_range(1.0, 100.0));
  o.angular_step_deg = config.get<double>("angular_step_deg", o.angular_step_deg, in_range(0.0625, 10.0));
  o.fov_deg = config.get<double>("fov_deg", o.fov_deg, in_range(1.0, 360.0));
  o.remission = config.get<bool>("remission", o.remission);
  o.range_min_m = config.get<double>("range_min_m", o.range_min_m, in_range(0.0, 10.0));
  o.range_max_m = config.get<double>("range_max_m", o.range_max_m, in_range(0.5, 100.0));
  o.sensor_x_m = config.get<double>("sensor_x_m", o.sensor_x_m, in_range(-5.0, 5.0));
  o.sensor_y_m = config.get<double>("sensor_y_m", o.sensor_y_m, in_range(-5.0, 5.0));
  o.sensor_theta_rad = config.get<double>("sensor_theta_rad", o.sensor_theta_rad, in_range(-4.0, 4.0));
  o.max_telegram_bytes = static_cast<std::size_t>(
      config.get<int>("max_telegram_bytes", static_cast<int>(o.max_telegram_bytes), in_range(1024, 1 << 24)));
  o.max_device_time_jump_ms = config.get<int>("max_device_time_jump_ms", o.max_device_time_jump_ms, in_range(10, 60'000));
  o.contamination_poll_ms =
      config.get<int>("contamination_poll_ms", o.contamination_poll_ms, in_range(0, 3'600'000));
  return o;
}

Reader::Reader(runtime::Node& node, const ReaderOptions& options) : node_(node), core_(options, outputs()) {
  node_.collect_counters([this]() -> decltype(auto) { return core_.counters(); });
  // DEGRADED, not STARTING: the runtime promotes STARTING to OK when its loop
  // starts, and we are not OK before scans flow.
  node_.set_state(pex::daemon_status_t::STATE_DEGRADED, "connecting to " + options.host);
  node_.every(std::chrono::milliseconds(20), [this](std::int64_t) {
    core_.poll(node_.monotonic_us());
  });
}

ReaderOutputs Reader::outputs() {
  ReaderOutputs out;
  out.connect = [this](std::string* error) {
    const ReaderOptions& o = core_.options();
    auto fd = hwio::tcp_connect(o.host, static_cast<std::uint16_t>(o.port), o.connect_timeout_ms);
    if (!fd) {
      *error = fd.error();
      return false;
    }
    fd_ = std::move(*fd);
    watch_id_ = node_.watch_fd(fd_.get(), [this] { on_readable(); });
    return true;
  };
  out.close = [this] {
    if (watch_id_ >= 0) node_.unwatch_fd(watch_id_);
    watch_id_ = -1;
    fd_.reset();
  };
  out.send = [this](std::string_view bytes, std::string* error) {
    return hwio::write_all(fd_.get(), bytes, core_.options().reply_timeout_ms, error);
  };
  out.publish_scan = [this](const pex::laser_scan_t& msg) { node_.publish(runtime::channels::kLidarScan, msg); };
  out.report = [this](const runtime::DaemonHealth& health) {
    node_.set_state(health.state, health.reason);
  };
  out.note = [](const std::string& text) { spdlog::info("{}", text); };
  out.error = [this](std::string_view key, const std::string& text) { node_.error(key, text); };
  out.reject = [this](std::string_view key, const std::string& text) { node_.reject(key, text); };
  return out;
}

void Reader::on_readable() {
  char buffer[16384];
  const std::int64_t now_us = node_.monotonic_us();
  while (fd_.valid()) {  // the core may close the connection on what it reads
    hwio::ReadResult r = hwio::read_some(fd_.get(), buffer, sizeof buffer);
    if (r.closed) {
      core_.on_closed(r.error, now_us);
      break;
    }
    if (r.bytes == 0) break;
    core_.on_bytes(std::string_view(buffer, r.bytes), now_us, node_.now_utime());
  }
}

}  // namespace pex::lidar_reader
