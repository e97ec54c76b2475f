#pragma once
// Node: one daemon's connection to the LCM bus, its poll loop, timers and health.
//
// Live and replay share one code path: live, LCM delivers raw bytes to
// dispatch(); offline, a log reader calls dispatch() with the logged bytes and
// the node's clock follows the log, so timers fire in log time.
//
// One clock seam (config key `clock`, read by run_daemon): with "system" the
// node stamps with the system clock and runs timers and timeouts on the
// monotonic clock; with "sim" it runs all of them on the simulator's SIM_CLOCK
// (as ROS's use_sim_time), driven through the same path as replay, so a
// simulation at 10x speed gives the daemons the same time line as one at 1x.
// The DAEMON_STATUS heartbeat and the systemd watchdog always stay on the
// monotonic clock, so health shows even when the simulator is paused or gone.
//
// Every subscription decodes defensively: a message that fails to decode, or
// whose handler refuses it (throws std::invalid_argument: bad content), is
// counted as rejected, logged at most once a second per channel, and dropped;
// the daemon keeps its state and goes on.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <spdlog/spdlog.h>

#include "runtime/bus_tap.hpp"

namespace lcm {
class LCM;
class LogFile;
}  // namespace lcm

namespace pex::runtime {

// The one way to refuse input, in a library or a handler: throw
// std::invalid_argument with the reason (NaN ranges, oversize arrays, a
// polygon that crosses itself, ...). The node counts it as a rejected message;
// any other std::exception counts as an error of the daemon, and is also
// survived. Libraries need nothing of the runtime for it, and a handler passes
// their refusals on untouched.

// Why `size` bytes are not one whole message of type `type_name` (fingerprint
// `hash`), whose decode() returned `used`: for the rejection's log line.
std::string decode_failure(const void* data, int size, int used, int64_t hash, const char* type_name);

// Logs at most one line per `period` for each key, and says how many it held back.
class RateLimitedLog {
 public:
  explicit RateLimitedLog(std::chrono::milliseconds period = std::chrono::seconds(1))
      : period_(period) {}
  void log(spdlog::level::level_enum level, const std::string& key, const std::string& text);
  // A line about `key` was just logged another way: its period starts now.
  void restart(const std::string& key);

 private:
  struct Entry {
    std::chrono::steady_clock::time_point last{};
    int64_t suppressed = 0;
  };
  std::chrono::milliseconds period_;
  std::map<std::string, Entry> entries_;
};

// Where a live node's time comes from (config key `clock`).
enum class ClockSource {
  kSystem,  // "system": stamps from the system clock, timers and timeouts on steady_clock
  kSim,     // "sim": everything on the latest SIM_CLOCK message (the simulator's clock)
};

struct NodeOptions {
  std::string name;                 // daemon name, as in DAEMON_STATUS
  std::string lcm_url;              // "" = LCM's default (LCM_DEFAULT_URL)
  bool offline = false;             // replay: no LCM; clock follows dispatched events
  std::string offline_output_log;   // offline: publish() writes here ("" = discard)
  double heartbeat_period_s = 1.0;
  // Live only: offline, the log's event times are the clock whatever this says
  // (a log need not hold SIM_CLOCK, e.g. the Intel data set).
  ClockSource clock = ClockSource::kSystem;
  // "sim": no SIM_CLOCK for this long (monotonic) after it ran = ERROR.
  double sim_clock_silence_s = 2.0;
};

class Node {
 public:
  using RawHandler = std::function<void(const void* data, int size, int64_t recv_utime)>;
  using Clock = std::chrono::microseconds;

  // Throws std::runtime_error if LCM cannot be created for the URL.
  explicit Node(NodeOptions options);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const { return options_.name; }
  bool offline() const { return options_.offline; }
  ClockSource clock_source() const { return options_.clock; }

  // Decodes each message on `channel` as Msg and calls `handler(msg)`.
  template <class Msg, class Handler>
  void subscribe(std::string_view channel, Handler handler) {
    subscribe_raw(channel, [handler](const void* data, int size, int64_t) {
      Msg msg{};  // value-initialised: lcm-gen types have no member initialisers
      // The decoders check every count against the bytes left before they
      // allocate (cmake/PexLcmBoundedDecode.cmake), so hostile bytes end here
      // as rejected input, through dispatch like any other refusal.
      const int used = msg.decode(data, 0, size);
      if (used != size)
        throw std::invalid_argument(decode_failure(data, size, used, Msg::getHash(), Msg::getTypeName()));
      handler(msg);
    });
  }
  void subscribe_raw(std::string_view channel, RawHandler handler);

  // Encodes and sends `msg` (offline: writes to the output log if any).
  template <class Msg>
  void publish(std::string_view channel, const Msg& msg) {
    std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    publish_raw(channel, buf.data(), static_cast<int>(buf.size()));
  }
  void publish_raw(std::string_view channel, const void* data, int size);

  // The shared path for live and replay: runs the handlers of `channel` on the
  // bytes, counting and surviving bad input. `recv_utime` is the receive time
  // (offline: the log event's time, which becomes the node's clock).
  void dispatch(std::string_view channel, const void* data, int size, int64_t recv_utime);

  // Calls `fn(now_utime())` every `period` of the node's clock: live "system",
  // steady_clock; live "sim", simulated time as SIM_CLOCK messages arrive (none
  // before the first); offline, log time. Missed periods are skipped, not burst.
  void every(std::chrono::microseconds period, std::function<void(int64_t now_utime)> fn);
  // Calls `fn()` whenever `fd` is readable (live only). Returns an id for unwatch().
  int watch_fd(int fd, std::function<void()> fn);
  void unwatch_fd(int id);
  // Runs once when the node stops (live: SIGTERM; offline: end of log).
  void on_shutdown(std::function<void()> fn) { shutdown_hooks_.push_back(std::move(fn)); }

  // For stamps (`utime`): us since the epoch. Live "system": the system clock;
  // live "sim": the latest good SIM_CLOCK utime; offline: the current event's
  // time. 0 while clock_started() is false.
  int64_t now_utime() const;
  // For timeouts and rates: us that never go back (differences only). Live
  // "system": steady_clock, unaffected by the system clock being set; live "sim"
  // and offline: the same value as now_utime().
  int64_t monotonic_us() const;
  // False until the clock has a time: live "sim" before the first good
  // SIM_CLOCK, offline before the first event. Always true for "system".
  bool clock_started() const { return clock_started_; }

  // Health bookkeeping, published in DAEMON_STATUS.
  void reject(std::string_view what_key, const std::string& text);  // bad input
  void error(std::string_view what_key, const std::string& text);   // own error
  void set_state(int8_t state, std::string reason = {});            // daemon_status_t::STATE_*
  int64_t& counter(const std::string& name);                        // daemon-specific counter
  // A component's counters in DAEMON_STATUS: `source()` returns (a reference
  // to) an object whose `visit_counters(v) const` names each counter once,
  // beside its value: v.event(name, n) for an event count (shown once it has
  // counted, as the node's own are) and v.total(name, n) for a total or a
  // state (always shown). The node reads every source before each
  // DAEMON_STATUS it publishes (a state change publishes one at once) and when
  // counters() is asked, so a daemon registers a component once and never
  // copies a counter by hand; a source costs nothing between heartbeats.
  template <class Source>
  void collect_counters(Source source) {
    counter_sources_.push_back([this, source] { show_counters(source()); });
  }
  // A component's counters, once, now (what collect_counters does at those points).
  template <class Counters>
  void show_counters(const Counters& counters) {
    struct Shown {
      Node& node;
      void event(const char* name, int64_t value) {
        if (value != 0) node.counter(name) = value;
      }
      void total(const std::string& name, int64_t value) { node.counter(name) = value; }
    } shown{*this};
    counters.visit_counters(shown);
  }
  // As DAEMON_STATUS carries them (every collect_counters source read first).
  const std::map<std::string, int64_t>& counters() {
    refresh_counters();
    return counters_;
  }
  int64_t msgs_rejected() const { return msgs_rejected_; }
  int64_t errors() const { return errors_; }
  // The state DAEMON_STATUS carries: the daemon's own, made at least DEGRADED
  // while a "sim" node waits for its first SIM_CLOCK and ERROR while the clock
  // has been silent for sim_clock_silence_s of monotonic time.
  int8_t published_state() const;

  // Live loop: polls LCM, fds and timers until request_stop() or a signal.
  void run();
  void request_stop() { stop_ = true; }
  bool stopping() const { return stop_; }
  // Offline: dispatches every event of the LCM logs in order of event time
  // (ties: the earlier log on the command line first), then stops. Returns the
  // number of events read. Throws std::runtime_error if a log is unreadable.
  int64_t replay_logs(const std::vector<std::string>& paths);
  int64_t replay_log(const std::string& path) { return replay_logs({path}); }
  // Runs shutdown hooks (once) and publishes a last STATE_STOPPING status.
  void shutdown();

  // Sets the signal fd (SIGINT/SIGTERM) the live loop also watches.
  void set_signal_fd(int fd) { signal_fd_ = fd; }

 private:
  struct Timer {
    int64_t period_us;
    int64_t next_us;  // 0 on a driven clock: starts at the clock's next time
    std::function<void(int64_t)> fn;
  };

  // Heartbeat and watchdog: live, on steady_clock whatever `clock` says, so
  // health is published while the simulator is paused or gone; offline, in log time.
  void every_on_system_clock(std::chrono::microseconds period, std::function<void(int64_t)> fn);
  void add_timer(std::vector<Timer>& timers, std::chrono::microseconds period, std::function<void(int64_t)> fn);
  void fire_due_timers(std::vector<Timer>& timers, int64_t now_us);
  void refresh_counters();  // every collect_counters source, now
  // The one path by which a driven clock (offline: log time; "sim": SIM_CLOCK)
  // moves: sets the time and fires the node's due timers (inside the live
  // loop, at the end of the loop's turn instead: see run()).
  void advance_clock(int64_t now_us);
  void on_sim_clock(const void* data, int size);
  void check_sim_clock_silence();
  void take_clock_ticks();  // "sim" on udpm: every SIM_CLOCK tick waiting on the tap
  void set_clock_problem(int8_t state, std::string why);
  void publish_status();
  struct Watch {
    int id;
    int fd;
    std::function<void()> fn;
  };

  NodeOptions options_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<BusTap> clock_tap_;  // "sim" on udpm: SIM_CLOCK read in this thread
  std::unique_ptr<lcm::LogFile> out_log_;
  std::map<std::string, std::vector<RawHandler>, std::less<>> handlers_;
  std::vector<Timer> timers_;         // on the node's clock
  std::vector<Timer> system_timers_;  // live: on steady_clock (heartbeat, watchdog)
  std::vector<Watch> watches_;
  std::vector<std::function<void()>> shutdown_hooks_;
  std::map<std::string, int64_t> counters_;
  std::vector<std::function<void()>> counter_sources_;  // collect_counters
  RateLimitedLog rate_limited_;
  // A new reason for the same state, at most every 10 s: see set_state.
  RateLimitedLog state_log_{std::chrono::seconds(10)};
  int next_watch_id_ = 1;
  int signal_fd_ = -1;
  bool stop_ = false;
  bool shut_down_ = false;
  // True when the clock is driven by events (offline, or live "sim") rather than read.
  bool driven_clock_ = false;
  bool clock_started_ = false;
  bool in_live_loop_ = false;          // run() fires the "sim" timers once per turn
  int64_t clock_now_us_ = 0;           // driven clock: its time (0 = none yet)
  int64_t last_clock_steady_us_ = 0;   // "sim": steady time of the last good SIM_CLOCK
  int8_t clock_problem_state_ = 0;     // "sim": state the clock imposes (with a reason) ...
  std::string clock_problem_;          // ... "" = none
  int64_t start_mono_us_ = 0;
  int64_t msgs_in_ = 0, msgs_out_ = 0, msgs_rejected_ = 0, errors_ = 0;
  std::string last_error_;
  int8_t state_ = 0;
  std::string state_reason_;
};

}  // namespace pex::runtime
