#pragma once
// pex-lidar-reader's logic without a socket, a node or a clock: the
// connection state machine (connect, log in, configure, stream, back off),
// framing and parsing (cola::StreamParser), the device clock
// (cola::DeviceClock) and LMDscandata -> laser_scan_t. Bytes and time in;
// connect/send/close requests, LIDAR_SCAN and health out, through
// ReaderOutputs. The daemon's shell (reader.hpp) owns the TCP socket and the
// node; the tests play the sensor.
//
// Times: `now_us` is a monotonic clock (timeouts, back-off; any epoch, never
// going back), `now_utime` the stamping clock (LIDAR_SCAN.utime).
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <pex/laser_scan_t.hpp>

#include "runtime/daemon_state.hpp"
#include "cola/cola.hpp"

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
  // A scan whose device time runs this much further ahead of the last
  // scan's than the host's time since it is refused (a device clock that
  // jumped); one whose device time is less than half a period after it, or
  // before it, too (a repeated or injected scan).
  int max_device_time_jump_ms = 500;
  // While streaming, ask the device's lens contamination measurement ("sRN
  // LCMstate") at once and then this often (0: never). A warning or an error
  // makes the reader DEGRADED, saying so: a dirty window loses echoes, which
  // the mapper and the explorer can only guess at. A device that refuses the
  // request (sFA) is not asked again on that connection.
  int contamination_poll_ms = 10000;

  cola::ScanConfig scan_config() const;
};

// Why a scan telegram is not one the configured sensor can send, "" if it is.
// Always: an LMS1xx's envelope (start -45 deg or later, end 225 deg or before
// in device angles, a step of 1/6 to 1 deg, 1 to 2000 beams, 10 to 100 Hz,
// DIST1 scale factor 1 or 2 and offset 0, as SICK's telegram listing has them).
// With configure_scan, also what we configured: the step, the first beam, the
// beam count (each within one step) and the frequency (within 5 %).
std::string implausible_scan(const cola::ScanData& scan, const cola::Channel& dist, const ReaderOptions& options);

// What DAEMON_STATUS counts under these names (docs/cola.md).
struct ReaderCounters {
  // Events, counted as they happen.
  std::int64_t connect_attempts = 0;
  std::int64_t disconnects = 0;          // connections lost or dropped by us
  std::int64_t scans_published = 0;
  std::int64_t malformed_telegrams = 0;  // framed, but not a telegram we can parse
  std::int64_t unexpected_replies = 0;   // not the answer awaited (late, or while streaming)
  std::int64_t unexpected_scans = 0;     // scan data before the configuration was done
  std::int64_t implausible_scans = 0;    // not what the configured sensor sends, too fast, or too old
  // The framer's totals, as of the last poll.
  std::int64_t skipped_bytes = 0;        // outside any telegram
  std::int64_t truncated_telegrams = 0;  // cut off by a new STX
  std::int64_t oversize_telegrams = 0;   // longer than max_telegram_bytes
  // The device clock's (cola::DeviceClock), over every connection.
  std::int64_t device_clock_outliers = 0;  // scans received more than 0.5 s off its estimate (a backlog read at once)
  std::int64_t device_clock_resets = 0;    // new offsets taken (the host clock stepped)
  // The lens contamination measurement's last answer (0 none, 1 warning,
  // 2 error, 3 serious error; -1 not read on this connection), and the
  // requests for it that went unanswered within reply_timeout_ms.
  std::int64_t contamination_level = -1;
  std::int64_t contamination_unanswered = 0;

  // By name, for DAEMON_STATUS (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    v.event("connect_attempts", connect_attempts);
    v.event("disconnects", disconnects);
    v.event("scans_published", scans_published);
    v.event("malformed_telegrams", malformed_telegrams);
    v.event("unexpected_replies", unexpected_replies);
    v.event("unexpected_scans", unexpected_scans);
    v.event("implausible_scans", implausible_scans);
    v.total("skipped_bytes", skipped_bytes);
    v.total("truncated_telegrams", truncated_telegrams);
    v.total("oversize_telegrams", oversize_telegrams);
    v.total("device_clock_outliers", device_clock_outliers);
    v.total("device_clock_resets", device_clock_resets);
    v.total("contamination_level", contamination_level);
    v.event("contamination_unanswered", contamination_unanswered);
  }
};

struct ReaderOutputs {
  // Opens the connection to host:port within connect_timeout_ms; false, with
  // the reason in *error, when it could not.
  std::function<bool(std::string* error)> connect;
  // Closes the open connection; the core expects no more bytes from it.
  std::function<void()> close;
  // Sends bytes on the open connection; false, with the reason in *error, when it could not.
  std::function<bool(std::string_view bytes, std::string* error)> send;
  std::function<void(const pex::laser_scan_t& msg)> publish_scan;
  // At every change of phase, and with every scan; counters() is current.
  std::function<void(const runtime::DaemonHealth& health)> report;
  // The connection's progress, for the log ("connected to ...", "streaming ...").
  std::function<void(const std::string& text)> note;
  // An error (the connection's), and input that was refused: `key` groups
  // them for rate-limited logging.
  std::function<void(std::string_view key, const std::string& text)> error;
  std::function<void(std::string_view key, const std::string& text)> reject;
};

class ReaderCore {
 public:
  enum class Phase { kDisconnected, kConfiguring, kStreaming };

  ReaderCore(const ReaderOptions& options, ReaderOutputs outputs);

  // Call often (the daemon: every 20 ms). Connects when the back-off is over,
  // drops a connection whose answer or scans are overdue, and counts framing
  // problems (one reject per poll that saw new ones).
  void poll(std::int64_t now_us);
  // Bytes read from the open connection, as they came (any split).
  void on_bytes(std::string_view bytes, std::int64_t now_us, std::int64_t now_utime);
  // The open connection ended: `error` says why, "" when the sensor closed it.
  void on_closed(const std::string& error, std::int64_t now_us);

  Phase phase() const { return phase_; }
  // The wait before the next connection attempt after the next failure.
  int backoff_ms() const { return backoff_ms_; }
  const ReaderOptions& options() const { return options_; }
  const ReaderCounters& counters() const { return counters_; }

 private:
  struct Step {
    std::string request;       // framed bytes
    std::string answer_type;   // "sAN", "sWA", "sEA"
    std::string answer_name;
  };

  void connect(std::int64_t now_us);
  void disconnect(const std::string& why, std::int64_t now_us);
  void on_reply(const cola::Telegram& telegram, std::int64_t now_us);
  void on_scan(const cola::ScanData& scan, std::int64_t now_us, std::int64_t now_utime);
  pex::laser_scan_t laser_scan(const cola::ScanData& scan, const cola::Channel& dist,
                               const cola::DeviceClock::Mapped& mapped) const;
  void send_next_step(std::int64_t now_us);
  void report(std::int8_t state, std::string reason);
  // Streaming: asks LCMstate when it is due; an answer overdue is counted.
  void poll_contamination(std::int64_t now_us);
  // Streaming: an answer to our LCMstate request, or a refusal of it.
  void on_contamination_reply(const cola::Telegram& telegram);
  // The health of a connection that streams: OK, or DEGRADED with the contamination.
  void report_streaming();

  ReaderOptions options_;
  ReaderOutputs outputs_;
  std::vector<Step> steps_;
  Phase phase_ = Phase::kDisconnected;
  cola::StreamParser parser_;
  cola::DeviceClock clock_;
  ReaderCounters counters_;
  std::size_t step_ = 0;
  std::int64_t step_sent_us_ = 0;
  std::int64_t last_scan_us_ = 0;
  std::uint32_t last_device_us_ = 0;  // device time of the last scan published
  bool have_device_us_ = false;
  std::int64_t next_attempt_us_ = 0;
  std::int64_t next_contamination_us_ = 0;       // when LCMstate is asked next
  std::int64_t contamination_asked_us_ = -1;     // our request awaits its answer since (-1: none)
  bool contamination_refused_ = false;           // this connection's device refused LCMstate
  int backoff_ms_ = 0;
  cola::Framer::Counters reported_framer_{};
};

}  // namespace pex::lidar_reader
