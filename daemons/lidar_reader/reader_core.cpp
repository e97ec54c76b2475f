#include "reader_core.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <pex/daemon_status_t.hpp>

namespace pex::lidar_reader {

cola::ScanConfig ReaderOptions::scan_config() const {
  // Device angles: 0 deg to the right, 90 deg straight ahead.
  cola::ScanConfig c;
  c.frequency_centihz = static_cast<std::uint32_t>(std::lround(scan_frequency_hz * 100.0));
  c.angular_step_1e4deg = static_cast<std::uint32_t>(std::lround(angular_step_deg * 1e4));
  c.start_angle_1e4deg = static_cast<std::int32_t>(std::lround((90.0 - 0.5 * fov_deg) * 1e4));
  c.stop_angle_1e4deg = static_cast<std::int32_t>(std::lround((90.0 + 0.5 * fov_deg) * 1e4));
  return c;
}

std::string implausible_scan(const cola::ScanData& scan, const cola::Channel& dist, const ReaderOptions& options) {
  const auto n = static_cast<std::int64_t>(dist.data.size());
  const std::int64_t step = dist.angular_step_1e4deg;
  const std::int64_t first = dist.start_angle_1e4deg;
  const std::int64_t last = first + (n - 1) * step;
  auto deg = [](std::int64_t a) { return std::to_string(static_cast<double>(a) * 1e-4) + " deg"; };
  if (n < 1 || n > 2000) return std::to_string(n) + " beams";
  if (step < 1667 || step > 10000) return "angular step " + deg(step);
  if (first < -450000 || last > 2250000) return "beams from " + deg(first) + " to " + deg(last);
  if (scan.scan_frequency_centihz < 1000 || scan.scan_frequency_centihz > 10000)
    return "scan frequency " + std::to_string(scan.scan_frequency_centihz * 0.01) + " Hz";
  // Distances are value x scale + offset: any other scale or an offset made
  // ranges negative or beyond 1e29 m (found by the fuzz target cola).
  if (!(dist.scale_factor == 1.0f || dist.scale_factor == 2.0f) || dist.scale_offset != 0.0f)
    return "DIST1 scale factor " + std::to_string(dist.scale_factor) + ", offset " +
           std::to_string(dist.scale_offset);
  if (!options.configure_scan) return "";
  const cola::ScanConfig want = options.scan_config();
  const std::int64_t want_step = want.angular_step_1e4deg;
  const std::int64_t want_beams = (want.stop_angle_1e4deg - want.start_angle_1e4deg) / want_step + 1;
  if (step != want_step) return "angular step " + deg(step) + ", configured " + deg(want_step);
  if (std::abs(first - want.start_angle_1e4deg) > want_step)
    return "first beam at " + deg(first) + ", configured " + deg(want.start_angle_1e4deg);
  if (std::abs(n - want_beams) > 1) return std::to_string(n) + " beams, configured " + std::to_string(want_beams);
  if (std::abs(static_cast<double>(scan.scan_frequency_centihz) - want.frequency_centihz) > 0.05 * want.frequency_centihz)
    return "scan frequency " + std::to_string(scan.scan_frequency_centihz * 0.01) + " Hz, configured " +
           std::to_string(want.frequency_centihz * 0.01) + " Hz";
  return "";
}

ReaderCore::ReaderCore(const ReaderOptions& options, ReaderOutputs outputs)
    : options_(options),
      outputs_(std::move(outputs)),
      parser_(cola::Framer::Options{options_.max_telegram_bytes}) {
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
}

void ReaderCore::poll(std::int64_t now_us) {
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
      } else {
        poll_contamination(now_us);
      }
      break;
  }
  // Framing problems are counted as rejected input, once each.
  const auto& f = parser_.framer_counters();
  if (f.truncated > reported_framer_.truncated || f.oversize > reported_framer_.oversize) {
    outputs_.reject("telegram", "truncated or oversize telegram dropped");
  }
  counters_.skipped_bytes = static_cast<std::int64_t>(f.skipped_bytes);
  counters_.truncated_telegrams = static_cast<std::int64_t>(f.truncated);
  counters_.oversize_telegrams = static_cast<std::int64_t>(f.oversize);
  reported_framer_ = f;
}

void ReaderCore::connect(std::int64_t now_us) {
  ++counters_.connect_attempts;
  std::string error;
  if (!outputs_.connect(&error)) {
    disconnect(error, now_us);
    return;
  }
  parser_.reset();
  clock_.reset();
  have_device_us_ = false;  // a restarted device starts its clock again
  // Another connection, maybe another device: its window is read afresh.
  counters_.contamination_level = -1;
  contamination_asked_us_ = -1;
  contamination_refused_ = false;
  phase_ = Phase::kConfiguring;
  step_ = 0;
  const std::string address = options_.host + ":" + std::to_string(options_.port);
  outputs_.note("connected to " + address + ", configuring");
  report(pex::daemon_status_t::STATE_DEGRADED, "configuring the sensor");
  send_next_step(now_us);
}

void ReaderCore::disconnect(const std::string& why, std::int64_t now_us) {
  const bool was_connected = phase_ != Phase::kDisconnected;
  if (was_connected) {
    outputs_.close();
    ++counters_.disconnects;
  }
  phase_ = Phase::kDisconnected;
  next_attempt_us_ = now_us + 1000ll * backoff_ms_;
  outputs_.error("connection", why + "; retry in " + std::to_string(backoff_ms_) + " ms");
  report(pex::daemon_status_t::STATE_ERROR,
         "sensor " + options_.host + ":" + std::to_string(options_.port) + " unavailable: " + why);
  backoff_ms_ = std::min(backoff_ms_ * 2, options_.reconnect_max_ms);
}

void ReaderCore::send_next_step(std::int64_t now_us) {
  std::string error;
  step_sent_us_ = now_us;
  if (!outputs_.send(steps_[step_].request, &error)) {
    disconnect("sending " + steps_[step_].answer_name + ": " + error, now_us);
  }
}

void ReaderCore::on_bytes(std::string_view bytes, std::int64_t now_us, std::int64_t now_utime) {
  if (phase_ == Phase::kDisconnected) return;  // left over from a connection we dropped
  for (auto& event : parser_.push(bytes)) {
    if (auto* scan = std::get_if<cola::ScanEvent>(&event)) {
      on_scan(scan->scan, now_us, now_utime);
    } else if (auto* reply = std::get_if<cola::ReplyEvent>(&event)) {
      on_reply(reply->telegram, now_us);
    } else {
      outputs_.reject("telegram", "malformed telegram: " + std::get<cola::ErrorEvent>(event).message);
      ++counters_.malformed_telegrams;
    }
    if (phase_ == Phase::kDisconnected) return;  // a reply may have ended the connection
  }
}

void ReaderCore::on_closed(const std::string& error, std::int64_t now_us) {
  disconnect(error.empty() ? "sensor closed the connection" : error, now_us);
}

void ReaderCore::on_reply(const cola::Telegram& t, std::int64_t now_us) {
  if (phase_ == Phase::kStreaming && contamination_asked_us_ >= 0 &&
      ((t.type == "sRA" && t.name == "LCMstate") || t.type == "sFA")) {
    on_contamination_reply(t);
    return;
  }
  if (phase_ != Phase::kConfiguring) {
    ++counters_.unexpected_replies;
    return;
  }
  const Step& expected = steps_[step_];
  if (t.type == "sFA") {
    disconnect("sensor refused " + expected.answer_name + " (sFA " + (t.args.empty() ? "" : t.args[0]) + ")", now_us);
    return;
  }
  if (t.type != expected.answer_type || t.name != expected.answer_name) {
    ++counters_.unexpected_replies;
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
  next_contamination_us_ = now_us;  // asked at the next poll
  backoff_ms_ = options_.reconnect_initial_ms;
  outputs_.note("streaming scans from " + options_.host + ":" + std::to_string(options_.port));
}

void ReaderCore::on_scan(const cola::ScanData& scan, std::int64_t now_us, std::int64_t now_utime) {
  if (phase_ != Phase::kStreaming) {
    ++counters_.unexpected_scans;
    return;
  }
  const cola::Channel* dist = scan.find_channel("DIST1");
  if (!dist || dist->data.empty() || dist->angular_step_1e4deg == 0) {
    outputs_.reject("scan", "scan telegram without a usable DIST1 channel");
    return;
  }
  std::string why = implausible_scan(scan, *dist, options_);
  if (why.empty() && have_device_us_) {
    // Against the last scan taken (device time wraps every 71.6 min): sooner
    // than half a period, or back in time, is a repeated or injected scan;
    // further ahead than the host's time since then allows, a clock that
    // jumped. Either would also reset the device clock's offset window.
    const auto since_us = static_cast<std::int32_t>(scan.time_since_startup_us - last_device_us_);
    const std::int64_t half_period_us = 50'000'000 / std::max<std::int64_t>(scan.scan_frequency_centihz, 1);
    const std::int64_t host_since_us = now_us - last_scan_us_;
    if (since_us < half_period_us)
      why = "device time " + std::to_string(since_us) + " us after the last scan's";
    else if (since_us > host_since_us + static_cast<std::int64_t>(options_.max_device_time_jump_ms) * 1000)
      why = "device time " + std::to_string(since_us / 1000) + " ms after the last scan's, " +
            std::to_string(host_since_us / 1000) + " ms on the host";
  }
  if (!why.empty()) {
    // Refused, and not taken as a sign of life: a stream of them ends in the
    // stale timeout, a reconnect and a new configuration.
    ++counters_.implausible_scans;
    outputs_.reject("implausible scan", "implausible scan: " + why);
    return;
  }
  last_scan_us_ = now_us;
  last_device_us_ = scan.time_since_startup_us;
  have_device_us_ = true;
  // Device times map to host time through the offset observed at reception.
  const auto mapped = clock_.map(scan.time_since_startup_us, scan.time_of_transmission_us, now_utime);
  counters_.device_clock_outliers = static_cast<std::int64_t>(clock_.outliers());
  counters_.device_clock_resets = static_cast<std::int64_t>(clock_.resets());
  outputs_.publish_scan(laser_scan(scan, *dist, mapped));
  ++counters_.scans_published;
  report_streaming();
}

void ReaderCore::poll_contamination(std::int64_t now_us) {
  if (options_.contamination_poll_ms <= 0 || contamination_refused_) return;
  if (contamination_asked_us_ >= 0) {
    if (now_us - contamination_asked_us_ <= 1000ll * options_.reply_timeout_ms) return;
    // Unanswered: the scans still come (a hung device ends in the stale
    // timeout), so the connection stays; asked again at the next period.
    ++counters_.contamination_unanswered;
    outputs_.error("contamination", "no answer to LCMstate within " + std::to_string(options_.reply_timeout_ms) + " ms");
    contamination_asked_us_ = -1;
    return;
  }
  if (now_us < next_contamination_us_) return;
  std::string error;
  if (!outputs_.send(cola::contamination_state_request(), &error)) {
    disconnect("sending LCMstate: " + error, now_us);
    return;
  }
  contamination_asked_us_ = now_us;
  next_contamination_us_ = now_us + 1000ll * options_.contamination_poll_ms;
}

void ReaderCore::on_contamination_reply(const cola::Telegram& t) {
  contamination_asked_us_ = -1;
  if (t.type == "sFA") {
    contamination_refused_ = true;
    outputs_.note("the sensor refused LCMstate (sFA " + (t.args.empty() ? std::string() : t.args[0]) +
                  "): its window's contamination is not watched on this connection");
    return;
  }
  const auto level = cola::contamination_level(t);
  if (!level) {
    outputs_.reject("contamination", "LCMstate answer with " + std::to_string(t.args.size()) +
                                         " arguments, or a level not 0-3: the last level kept");
    ++counters_.malformed_telegrams;
    return;
  }
  const auto before = counters_.contamination_level;
  counters_.contamination_level = static_cast<std::int64_t>(*level);
  if (counters_.contamination_level != before && before >= 0)
    outputs_.note("lens contamination level " + std::to_string(before) + " -> " +
                  std::to_string(counters_.contamination_level));
  report_streaming();
}

void ReaderCore::report_streaming() {
  switch (counters_.contamination_level) {
    case 1:
      report(pex::daemon_status_t::STATE_DEGRADED, "lens contamination warning (LCMstate 1): clean the laser's window");
      return;
    case 2:
      report(pex::daemon_status_t::STATE_DEGRADED,
             "lens contamination error (LCMstate 2): the laser's window is dirty, echoes are lost; clean it");
      return;
    case 3:
      report(pex::daemon_status_t::STATE_DEGRADED,
             "serious lens contamination error (LCMstate 3): the laser's window is dirty, echoes are lost; clean it");
      return;
    default:
      report(pex::daemon_status_t::STATE_OK, "");
  }
}

pex::laser_scan_t ReaderCore::laser_scan(const cola::ScanData& scan, const cola::Channel& dist,
                                         const cola::DeviceClock::Mapped& mapped) const {
  constexpr double kDegToRad = std::numbers::pi / 180.0;
  pex::laser_scan_t msg{};
  msg.utime = mapped.host_us;
  msg.device_utime = mapped.device_us;
  msg.scan_counter = scan.scan_counter;
  msg.angle_min = static_cast<float>((dist.start_angle_1e4deg * 1e-4 - 90.0) * kDegToRad);
  msg.angle_increment = static_cast<float>(dist.angular_step_1e4deg * 1e-4 * kDegToRad);
  msg.range_min = static_cast<float>(options_.range_min_m);
  msg.range_max = static_cast<float>(options_.range_max_m);
  msg.scan_time = scan.scan_frequency_centihz > 0 ? 100.0f / static_cast<float>(scan.scan_frequency_centihz) : 0.0f;
  msg.sensor_x = static_cast<float>(options_.sensor_x_m);
  msg.sensor_y = static_cast<float>(options_.sensor_y_m);
  msg.sensor_theta = static_cast<float>(options_.sensor_theta_rad);
  msg.ranges = cola::distances_m(dist);
  msg.nranges = static_cast<std::int32_t>(msg.ranges.size());
  if (const cola::Channel* rssi = scan.find_channel("RSSI1"); rssi && rssi->data.size() == dist.data.size()) {
    msg.intensities.assign(rssi->data.begin(), rssi->data.end());
  }
  msg.nintensities = static_cast<std::int32_t>(msg.intensities.size());
  return msg;
}

void ReaderCore::report(std::int8_t state, std::string reason) {
  outputs_.report(runtime::DaemonHealth{state, std::move(reason)});
}

}  // namespace pex::lidar_reader
