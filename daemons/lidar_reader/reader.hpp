#pragma once
// pex-lidar-reader's parts: options from config/lidar_reader.toml and the
// connection state machine (connect, log in, configure, stream, back off).
// Its timeouts and back-off run on the node's monotonic clock (simulated time
// with clock = "sim"); `now_us` arguments below are that clock's.
#include <cstdint>
#include <string>
#include <vector>

#include "cola/cola.hpp"
#include "hwio/hwio.hpp"
#include "runtime/config.hpp"

namespace pex::runtime {
class Node;
}

namespace pex::lidar_reader {

struct ReaderOptions {
  std::string host = "192.168.0.1";      // the LMS1xx factory address; the sim uses 127.0.0.1
  int port = 2111;
  int connect_timeout_ms = 1000;
  int reply_timeout_ms = 2000;           // per configuration request
  int stale_timeout_ms = 1000;           // no scan for this long while streaming -> reconnect
  int reconnect_initial_ms = 200;        // back-off starts here and doubles ...
  int reconnect_max_ms = 5000;           // ... up to this
  bool configure_scan = true;            // send mLMPsetscancfg (else keep the device's)
  double scan_frequency_hz = 25.0;
  double angular_step_deg = 0.5;
  double fov_deg = 270.0;                // symmetric about straight ahead
  bool remission = true;                 // request the RSSI1 channel
  double range_min_m = 0.05;
  double range_max_m = 20.0;
  double sensor_x_m = 0.0, sensor_y_m = 0.0, sensor_theta_rad = 0.0;  // in the base frame
  std::size_t max_telegram_bytes = 65536;

  cola::ScanConfig scan_config() const;
};

ReaderOptions load_options(runtime::ConfigReader& config);

// Owns the TCP connection to the sensor and publishes LIDAR_SCAN.
class Reader {
 public:
  Reader(runtime::Node& node, ReaderOptions options);

 private:
  enum class Phase { kDisconnected, kConfiguring, kStreaming };
  struct Step {
    std::string request;       // framed bytes
    std::string answer_type;   // "sAN", "sWA", "sEA"
    std::string answer_name;
  };

  void poll(std::int64_t now_us);
  void connect(std::int64_t now_us);
  void disconnect(const std::string& why, std::int64_t now_us);
  void on_readable();
  void on_reply(const cola::Telegram& telegram, std::int64_t now_us);
  void on_scan(const cola::ScanData& scan, std::int64_t now_us);
  void send_next_step(std::int64_t now_us);

  runtime::Node& node_;
  ReaderOptions options_;
  std::vector<Step> steps_;
  Phase phase_ = Phase::kDisconnected;
  hwio::Fd fd_;
  int watch_id_ = -1;
  cola::StreamParser parser_;
  cola::DeviceClock clock_;
  std::size_t step_ = 0;
  std::int64_t step_sent_us_ = 0;
  std::int64_t last_scan_us_ = 0;
  std::int64_t next_attempt_us_ = 0;
  int backoff_ms_ = 0;
  cola::Framer::Counters reported_framer_{};
};

}  // namespace pex::lidar_reader
