#include "reader.hpp"

#include <chrono>
#include <cmath>
#include <numbers>

#include <pex/daemon_status_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <spdlog/spdlog.h>

#include "runtime/channels.hpp"
#include "runtime/node.hpp"

namespace pex::lidar_reader {

using runtime::in_range;

cola::ScanConfig ReaderOptions::scan_config() const {
  // Device angles: 0 deg to the right, 90 deg straight ahead.
  cola::ScanConfig c;
  c.frequency_centihz = static_cast<std::uint32_t>(std::lround(scan_frequency_hz * 100.0));
  c.angular_step_1e4deg = static_cast<std::uint32_t>(std::lround(angular_step_deg * 1e4));
  c.start_angle_1e4deg = static_cast<std::int32_t>(std::lround((90.0 - 0.5 * fov_deg) * 1e4));
  c.stop_angle_1e4deg = static_cast<std::int32_t>(std::lround((90.0 + 0.5 * fov_deg) * 1e4));
  return c;
}

ReaderOptions load_options(runtime::ConfigReader& config) {
  ReaderOptions o;
  o.host = config.get<std::string>("host", o.host);
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
  return o;
}

Reader::Reader(runtime::Node& node, ReaderOptions options)
    : node_(node), options_(std::move(options)), parser_(cola::Framer::Options{options_.max_telegram_bytes}) {
  // The login and configuration sequence of SICK's telegram listing.
  steps_.push_back({cola::set_access_mode_request(cola::kUserLevelAuthorizedClient, cola::kPasswordAuthorizedClient),
                    "sAN", "SetAccessMode"});
  if (options_.configure_scan) {
    steps_.push_back({cola::set_scan_config_request(options_.scan_config()), "sAN", "mLMPsetscancfg"});
  }
  cola::ScanDataConfig data_config;
  data_config.remission = options_.remission;
  steps_.push_back({cola::scan_data_config_request(data_config), "sWA", "LMDscandatacfg"});
  steps_.push_back({cola::output_range_request(options_.scan_config()), "sWA", "LMPoutputRange"});
  steps_.push_back({cola::start_measurement_request(), "sAN", "LMCstartmeas"});
  steps_.push_back({cola::run_request(), "sAN", "Run"});
  steps_.push_back({cola::scan_output_request(true), "sEA", "LMDscandata"});
  backoff_ms_ = options_.reconnect_initial_ms;
  // DEGRADED, not STARTING: the runtime promotes STARTING to OK when its loop
  // starts, and we are not OK before scans flow.
  node_.set_state(pex::daemon_status_t::STATE_DEGRADED, "connecting to " + options_.host);
  node_.every(std::chrono::milliseconds(20), [this](std::int64_t) { poll(node_.monotonic_us()); });
}

void Reader::poll(std::int64_t now_us) {
  switch (phase_) {
    case Phase::kDisconnected:
      if (now_us >= next_attempt_us_) connect(now_us);
      break;
    case Phase::kConfiguring:
      if (now_us - step_sent_us_ > 1000ll * options_.reply_timeout_ms) {
        disconnect("no answer to " + steps_[step_].answer_name + " within " +
                       std::to_string(options_.reply_timeout_ms) + " ms",
                   now_us);
      }
      break;
    case Phase::kStreaming:
      if (now_us - last_scan_us_ > 1000ll * options_.stale_timeout_ms) {
        disconnect("no scan for " + std::to_string(options_.stale_timeout_ms) + " ms", now_us);
      }
      break;
  }
  // Framing problems are counted as rejected input, once each.
  const auto& f = parser_.framer_counters();
  if (f.truncated > reported_framer_.truncated || f.oversize > reported_framer_.oversize) {
    node_.reject("telegram", "truncated or oversize telegram dropped");
  }
  node_.counter("skipped_bytes") = static_cast<std::int64_t>(f.skipped_bytes);
  node_.counter("truncated_telegrams") = static_cast<std::int64_t>(f.truncated);
  node_.counter("oversize_telegrams") = static_cast<std::int64_t>(f.oversize);
  reported_framer_ = f;
}

void Reader::connect(std::int64_t now_us) {
  ++node_.counter("connect_attempts");
  auto fd = hwio::tcp_connect(options_.host, static_cast<std::uint16_t>(options_.port), options_.connect_timeout_ms);
  if (!fd) {
    disconnect(fd.error(), now_us);
    return;
  }
  fd_ = std::move(*fd);
  parser_.reset();
  clock_.reset();
  watch_id_ = node_.watch_fd(fd_.get(), [this] { on_readable(); });
  phase_ = Phase::kConfiguring;
  step_ = 0;
  spdlog::info("connected to {}:{}, configuring", options_.host, options_.port);
  node_.set_state(pex::daemon_status_t::STATE_DEGRADED, "configuring the sensor");
  send_next_step(now_us);
}

void Reader::disconnect(const std::string& why, std::int64_t now_us) {
  if (watch_id_ >= 0) node_.unwatch_fd(watch_id_);
  watch_id_ = -1;
  const bool was_connected = fd_.valid();
  fd_.reset();
  phase_ = Phase::kDisconnected;
  next_attempt_us_ = now_us + 1000ll * backoff_ms_;
  node_.error("connection", why + "; retry in " + std::to_string(backoff_ms_) + " ms");
  node_.set_state(pex::daemon_status_t::STATE_ERROR, "sensor " + options_.host + ":" + std::to_string(options_.port) +
                                                          " unavailable: " + why);
  if (was_connected) ++node_.counter("disconnects");
  backoff_ms_ = std::min(backoff_ms_ * 2, options_.reconnect_max_ms);
}

void Reader::send_next_step(std::int64_t now_us) {
  std::string error;
  step_sent_us_ = now_us;
  if (!hwio::write_all(fd_.get(), steps_[step_].request, options_.reply_timeout_ms, &error)) {
    disconnect("sending " + steps_[step_].answer_name + ": " + error, now_us);
  }
}

void Reader::on_readable() {
  char buffer[16384];
  const std::int64_t now_us = node_.monotonic_us();
  for (;;) {
    if (!fd_.valid()) return;
    hwio::ReadResult r = hwio::read_some(fd_.get(), buffer, sizeof buffer);
    if (r.closed) {
      disconnect(r.error.empty() ? "sensor closed the connection" : r.error, now_us);
      return;
    }
    if (r.bytes == 0) return;
    for (auto& event : parser_.push(std::string_view(buffer, r.bytes))) {
      if (auto* scan = std::get_if<cola::ScanEvent>(&event)) {
        on_scan(scan->scan, now_us);
      } else if (auto* reply = std::get_if<cola::ReplyEvent>(&event)) {
        on_reply(reply->telegram, now_us);
      } else {
        node_.reject("telegram", "malformed telegram: " + std::get<cola::ErrorEvent>(event).message);
        ++node_.counter("malformed_telegrams");
      }
      if (!fd_.valid()) return;  // a reply may have ended the connection
    }
  }
}

void Reader::on_reply(const cola::Telegram& t, std::int64_t now_us) {
  if (phase_ != Phase::kConfiguring) {
    ++node_.counter("unexpected_replies");
    return;
  }
  const Step& expected = steps_[step_];
  if (t.type == "sFA") {
    disconnect("sensor refused " + expected.answer_name + " (sFA " + (t.args.empty() ? "" : t.args[0]) + ")", now_us);
    return;
  }
  if (t.type != expected.answer_type || t.name != expected.answer_name) {
    ++node_.counter("unexpected_replies");
    return;  // e.g. a late answer: keep waiting for ours
  }
  // Answers with a result: SetAccessMode/Run 1 = success; mLMPsetscancfg 0 = ok.
  const std::string result = t.args.empty() ? "" : t.args[0];
  bool ok = true;
  if (t.name == "SetAccessMode" || t.name == "Run") ok = result == "1";
  if (t.name == "mLMPsetscancfg") ok = result == "0";
  if (!ok) {
    disconnect("sensor answered " + t.name + " " + result, now_us);
    return;
  }
  if (++step_ < steps_.size()) {
    send_next_step(now_us);
    return;
  }
  phase_ = Phase::kStreaming;
  last_scan_us_ = now_us;
  backoff_ms_ = options_.reconnect_initial_ms;
  spdlog::info("streaming scans from {}:{}", options_.host, options_.port);
}

void Reader::on_scan(const cola::ScanData& scan, std::int64_t now_us) {
  if (phase_ != Phase::kStreaming) {
    ++node_.counter("unexpected_scans");
    return;
  }
  const cola::Channel* dist = scan.find_channel("DIST1");
  if (!dist || dist->data.empty() || dist->angular_step_1e4deg == 0) {
    node_.reject("scan", "scan telegram without a usable DIST1 channel");
    return;
  }
  last_scan_us_ = now_us;
  const std::int64_t host_now = node_.now_utime();
  // Device times map to host time through the offset observed at reception.
  const auto mapped = clock_.map(scan.time_since_startup_us, scan.time_of_transmission_us, host_now);
  constexpr double kDegToRad = std::numbers::pi / 180.0;
  pex::laser_scan_t msg{};
  msg.utime = mapped.host_us;
  msg.device_utime = mapped.device_us;
  msg.scan_counter = scan.scan_counter;
  msg.angle_min = static_cast<float>((dist->start_angle_1e4deg * 1e-4 - 90.0) * kDegToRad);
  msg.angle_increment = static_cast<float>(dist->angular_step_1e4deg * 1e-4 * kDegToRad);
  msg.range_min = static_cast<float>(options_.range_min_m);
  msg.range_max = static_cast<float>(options_.range_max_m);
  msg.scan_time = scan.scan_frequency_centihz > 0 ? 100.0f / static_cast<float>(scan.scan_frequency_centihz) : 0.0f;
  msg.sensor_x = static_cast<float>(options_.sensor_x_m);
  msg.sensor_y = static_cast<float>(options_.sensor_y_m);
  msg.sensor_theta = static_cast<float>(options_.sensor_theta_rad);
  msg.ranges = cola::distances_m(*dist);
  msg.nranges = static_cast<std::int32_t>(msg.ranges.size());
  if (const cola::Channel* rssi = scan.find_channel("RSSI1"); rssi && rssi->data.size() == dist->data.size()) {
    msg.intensities.assign(rssi->data.begin(), rssi->data.end());
  }
  msg.nintensities = static_cast<std::int32_t>(msg.intensities.size());
  node_.publish(runtime::channels::kLidarScan, msg);
  ++node_.counter("scans_published");
  node_.set_state(pex::daemon_status_t::STATE_OK);
}

}  // namespace pex::lidar_reader
