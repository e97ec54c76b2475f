#include "runtime/node.hpp"

#include "runtime/daemon_state.hpp"

#include <poll.h>
#include <sys/signalfd.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

#include <pex/daemon_status_t.hpp>
#include <pex/sim_clock_t.hpp>

#include "runtime/channels.hpp"
#include "runtime/log_file_error.hpp"

namespace pex::runtime {

void RateLimitedLog::log(spdlog::level::level_enum level, const std::string& key,
                         const std::string& text) {
  auto& e = entries_[key];
  const auto now = std::chrono::steady_clock::now();
  if (e.last.time_since_epoch().count() != 0 && now - e.last < period_) {
    ++e.suppressed;
    return;
  }
  if (e.suppressed > 0)
    spdlog::log(level, "{} ({} more like it in the last {} ms)", text, e.suppressed,
                period_.count());
  else
    spdlog::log(level, "{}", text);
  e.last = now;
  e.suppressed = 0;
}

void RateLimitedLog::restart(const std::string& key) {
  auto& e = entries_[key];
  e.last = std::chrono::steady_clock::now();
  e.suppressed = 0;
}

namespace {

void on_lcm_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Node* node) {
  node->dispatch(channel, rbuf->data, static_cast<int>(rbuf->data_size), rbuf->recv_utime);
}

int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

int64_t steady_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

Node::Node(NodeOptions options) : options_(std::move(options)) {
  start_mono_us_ = steady_us();
  driven_clock_ = options_.offline || options_.clock == ClockSource::kSim;
  clock_started_ = !driven_clock_;
  if (!options_.offline) {
    lcm_ = options_.lcm_url.empty() ? std::make_unique<lcm::LCM>()
                                    : std::make_unique<lcm::LCM>(options_.lcm_url);
    if (!lcm_->good())
      throw std::runtime_error("cannot open LCM at '" +
                               (options_.lcm_url.empty() ? std::string("<default>")
                                                         : options_.lcm_url) +
                               "'");
  } else if (!options_.offline_output_log.empty()) {
    out_log_ = std::make_unique<lcm::LogFile>(options_.offline_output_log, "w");
    if (!out_log_->good())
      throw std::runtime_error("cannot write log '" + options_.offline_output_log + "'");
  }
  if (!options_.offline && options_.clock == ClockSource::kSim) {
    // On a udpm bus the clock comes through our own socket, read in this
    // thread (bus_tap.hpp says why); on other LCM providers through LCM.
    if (const auto address = parse_udpm_url(options_.lcm_url))
      clock_tap_ = std::make_unique<BusTap>(*address, std::string(channels::kSimClock));
    else
      subscribe_raw(channels::kSimClock, [this](const void* data, int size, int64_t) { on_sim_clock(data, size); });
    counters_["sim_clock_rejected"] = 0;
    set_clock_problem(pex::daemon_status_t::STATE_DEGRADED,
                      "waiting for the simulator's clock on " + std::string(channels::kSimClock));
  }
  every_on_system_clock(std::chrono::microseconds(static_cast<int64_t>(options_.heartbeat_period_s * 1e6)),
                        [this](int64_t) {
                          check_sim_clock_silence();
                          publish_status();
                        });
}

Node::~Node() = default;

int64_t Node::now_utime() const { return driven_clock_ ? clock_now_us_ : wall_utime(); }

int64_t Node::monotonic_us() const { return driven_clock_ ? clock_now_us_ : steady_us(); }

void Node::advance_clock(int64_t now_us) {
  clock_now_us_ = now_us;
  clock_started_ = true;
  if (!in_live_loop_) fire_due_timers(timers_, now_us);
}

void Node::on_sim_clock(const void* data, int size) {
  pex::sim_clock_t c{};
  std::string why;
  if (c.decode(data, 0, size) != size)
    why = "cannot decode " + std::to_string(size) + " bytes as " + pex::sim_clock_t::getTypeName();
  else if (c.utime <= 0 || c.sim_time_us < 0 || c.sim_time_us > c.utime)
    why = "utime " + std::to_string(c.utime) + " / sim_time_us " + std::to_string(c.sim_time_us) + " out of range";
  else if (!std::isfinite(c.speed_factor) || c.speed_factor <= 0.0)
    why = "speed_factor " + std::to_string(c.speed_factor) + " is not a positive number";
  else if (clock_started_ && c.utime < clock_now_us_)
    why = "went backwards from " + std::to_string(clock_now_us_) + " to " + std::to_string(c.utime) + " us";
  if (!why.empty()) {
    // Keep the last good time: a clock that jumps back would re-run timers and
    // make every timeout measured across the jump negative.
    ++counters_["sim_clock_rejected"];
    throw std::invalid_argument(why);
  }
  last_clock_steady_us_ = steady_us();
  // The problem (waiting, silence) ends before the timers run, so what they
  // publish already carries the daemon's own state.
  const int8_t before = published_state();
  if (!clock_problem_.empty()) {
    spdlog::info("{} running: simulated time {:.3f} s, x{} speed", channels::kSimClock, c.sim_time_us * 1e-6,
                 c.speed_factor);
    set_clock_problem(pex::daemon_status_t::STATE_OK, {});
  }
  if (published_state() != before && !shut_down_) publish_status();
  advance_clock(c.utime);
}

void Node::take_clock_ticks() {
  if (!clock_tap_) return;
  clock_tap_->drain([this](const void* data, int size) {
    try {
      on_sim_clock(data, size);
      ++msgs_in_;
    } catch (const std::invalid_argument& e) {
      reject(channels::kSimClock, std::string(channels::kSimClock) + ": " + e.what());
    }
  });
}

void Node::check_sim_clock_silence() {
  if (options_.offline || options_.clock != ClockSource::kSim || !clock_started_ || !clock_problem_.empty()) return;
  const int64_t silent_us = steady_us() - last_clock_steady_us_;
  if (silent_us <= static_cast<int64_t>(options_.sim_clock_silence_s * 1e6)) return;
  // Frozen simulated time freezes our timers and timeouts too: the daemon
  // cannot do its job, nor notice its inputs are gone, hence ERROR.
  set_clock_problem(pex::daemon_status_t::STATE_ERROR,
                    "no " + std::string(channels::kSimClock) + " for " + std::to_string(silent_us / 1000) +
                        " ms: the simulator is paused or gone; timers and timeouts are stopped");
}

void Node::set_clock_problem(int8_t state, std::string why) {
  if (!why.empty()) spdlog::warn("{}", why);
  clock_problem_state_ = why.empty() ? pex::daemon_status_t::STATE_OK : state;
  clock_problem_ = std::move(why);
  counters_["sim_clock_waiting"] = clock_problem_.empty() ? 0 : 1;
}

int8_t Node::published_state() const {
  if (clock_problem_.empty() || state_ == pex::daemon_status_t::STATE_STOPPING) return state_;
  return std::max(state_, clock_problem_state_);
}

void Node::subscribe_raw(std::string_view channel, RawHandler handler) {
  auto it = handlers_.find(channel);
  if (it == handlers_.end()) {
    it = handlers_.emplace(std::string(channel), std::vector<RawHandler>{}).first;
    if (lcm_) lcm_->subscribeFunction(std::string(channel), &on_lcm_message, this);
  }
  it->second.push_back(std::move(handler));
}

void Node::publish_raw(std::string_view channel, const void* data, int size) {
  ++msgs_out_;
  if (lcm_) {
    if (lcm_->publish(std::string(channel), data, static_cast<unsigned>(size)) != 0)
      error("publish", "cannot publish on " + std::string(channel));
  } else if (out_log_) {
    lcm::LogEvent ev{};
    ev.eventnum = msgs_out_;
    ev.timestamp = now_utime();
    ev.channel = std::string(channel);
    ev.datalen = size;
    ev.data = const_cast<void*>(data);
    out_log_->writeEvent(&ev);
  }
}

void Node::dispatch(std::string_view channel, const void* data, int size, int64_t recv_utime) {
  if (options_.offline) advance_clock(recv_utime);
  auto it = handlers_.find(channel);
  if (it == handlers_.end()) return;
  const int64_t rejected_before = msgs_rejected_;
  const int64_t errors_before = errors_;
  for (auto& h : it->second) {
    try {
      h(data, size, recv_utime);
    } catch (const std::invalid_argument& e) {
      reject(channel, std::string(channel) + ": " + e.what());
    } catch (const std::exception& e) {
      error(channel, std::string(channel) + ": handler failed: " + e.what());
    }
  }
  if (msgs_rejected_ == rejected_before && errors_ == errors_before) ++msgs_in_;
}

void Node::refresh_counters() {
  for (const auto& source : counter_sources_) source();
}

void Node::every(std::chrono::microseconds period, std::function<void(int64_t)> fn) {
  add_timer(timers_, period, std::move(fn));
}

void Node::every_on_system_clock(std::chrono::microseconds period, std::function<void(int64_t)> fn) {
  add_timer(options_.offline ? timers_ : system_timers_, period, std::move(fn));
}

void Node::add_timer(std::vector<Timer>& timers, std::chrono::microseconds period, std::function<void(int64_t)> fn) {
  const int64_t p = std::max<int64_t>(1, period.count());
  const bool driven = driven_clock_ && &timers == &timers_;
  // A driven clock's timers start at its next time (next_us == 0 means "not yet").
  timers.push_back({p, driven ? 0 : steady_us() + p, std::move(fn)});
}

int Node::watch_fd(int fd, std::function<void()> fn) {
  const int id = next_watch_id_++;
  watches_.push_back({id, fd, std::move(fn)});
  return id;
}

void Node::unwatch_fd(int id) {
  std::erase_if(watches_, [id](const Watch& w) { return w.id == id; });
}

void Node::fire_due_timers(std::vector<Timer>& timers, int64_t now_us) {
  for (size_t i = 0; i < timers.size(); ++i) {
    Timer& t = timers[i];
    if (t.next_us == 0) t.next_us = now_us + t.period_us;
    if (now_us < t.next_us) continue;
    // Skip missed periods instead of bursting to catch up.
    t.next_us += t.period_us * std::max<int64_t>(1, (now_us - t.next_us) / t.period_us + 1);
    try {
      t.fn(now_utime());
    } catch (const std::exception& e) {
      error("timer", std::string("timer failed: ") + e.what());
    }
  }
}

void Node::reject(std::string_view what_key, const std::string& text) {
  ++msgs_rejected_;
  ++errors_;
  last_error_ = text;
  rate_limited_.log(spdlog::level::warn, "reject:" + std::string(what_key), "rejected: " + text);
}

void Node::error(std::string_view what_key, const std::string& text) {
  ++errors_;
  last_error_ = text;
  rate_limited_.log(spdlog::level::err, "error:" + std::string(what_key), text);
}

void Node::set_state(int8_t state, std::string reason) {
  // A change of state is logged at once; a new reason for the same state at
  // most every 10 s (with the count held back): an input watch's reason
  // counts the time ("no SLAM_UPDATE for 3.4 s") and changed at every check,
  // which logged a line four times a second for as long as the input was
  // away (54-234 lines in a simulated mission of a wing building). The
  // systemd status line has the newest reason at every heartbeat either way.
  if (state != state_ || reason != state_reason_) {
    const auto level = state == pex::daemon_status_t::STATE_OK ? spdlog::level::info : spdlog::level::warn;
    const std::string text =
        fmt::format("state {}{}{}", daemon_state_name(state), reason.empty() ? "" : ": ", reason);
    if (state != state_) {
      spdlog::log(level, "{}", text);
      state_log_.restart("state");
    } else {
      state_log_.log(level, "state", text);
    }
  }
  const int8_t before = published_state();
  state_ = state;
  state_reason_ = std::move(reason);
  // A change of health is news: publish it now rather than at the next heartbeat.
  if (published_state() != before && !shut_down_) publish_status();
}

int64_t& Node::counter(const std::string& name) { return counters_[name]; }

void Node::publish_status() {
  refresh_counters();
  pex::daemon_status_t s;
  // Live, the heartbeat is the process's health in real time: wall-clock
  // stamped even on a "sim" clock, which may not have started or may be stopped.
  s.utime = options_.offline ? clock_now_us_ : wall_utime();
  s.name = options_.name;
  s.pid = static_cast<int32_t>(getpid());
  s.state = published_state();
  s.uptime_s = options_.offline ? 0.0 : (steady_us() - start_mono_us_) * 1e-6;
  s.msgs_in = msgs_in_;
  s.msgs_out = msgs_out_ + 1;  // counts this status message too
  s.msgs_rejected = msgs_rejected_;
  s.errors = errors_;
  s.last_error = last_error_;
  for (const auto& [k, v] : counters_) {
    s.counter_names.push_back(k);
    s.counter_values.push_back(v);
  }
  s.ncounters = static_cast<int32_t>(s.counter_names.size());
  publish(channels::kDaemonStatus, s);
  if (!options_.offline && state_ != pex::daemon_status_t::STATE_STOPPING) {
    const std::string& reason = clock_problem_.empty() ? state_reason_ : clock_problem_;
    const std::string text = std::string("STATUS=") + daemon_state_name(s.state) + (reason.empty() ? "" : " (" + reason + ")") +
                             ", in " + std::to_string(msgs_in_) + ", out " + std::to_string(msgs_out_) +
                             ", rejected " + std::to_string(msgs_rejected_);
    sd_notify(0, text.c_str());
  }
}

void Node::run() {
  if (state_ == pex::daemon_status_t::STATE_STARTING) set_state(pex::daemon_status_t::STATE_OK);
  uint64_t watchdog_usec = 0;
  if (sd_watchdog_enabled(0, &watchdog_usec) > 0 && watchdog_usec > 0)
    every_on_system_clock(std::chrono::microseconds(watchdog_usec / 2), [](int64_t) { sd_notify(0, "WATCHDOG=1"); });
  sd_notify(0, "READY=1");
  publish_status();

  // Every message waiting (LCM hands out one per call), at most this many,
  // so a flood on the bus cannot starve the fds.
  constexpr int kMaxMessagesPerTurn = 1000;
  const auto handle_waiting_messages = [this] {
    take_clock_ticks();  // a message the simulator sent after a tick is handled at that tick
    for (int i = 0; i < kMaxMessagesPerTurn && lcm_->handleTimeout(0) > 0; ++i) {
    }
  };
  in_live_loop_ = true;
  std::vector<pollfd> fds;
  while (!stop_) {
    const int64_t now = steady_us();
    int64_t next = now + 100'000;
    for (const auto& t : system_timers_) next = std::min(next, t.next_us);
    if (!driven_clock_)
      for (const auto& t : timers_) next = std::min(next, t.next_us);
    const int timeout_ms = static_cast<int>(std::max<int64_t>(0, (next - now + 999) / 1000));

    fds.clear();
    fds.push_back({lcm_->getFileno(), POLLIN, 0});
    fds.push_back({signal_fd_, POLLIN, 0});
    if (clock_tap_) fds.push_back({clock_tap_->fd(), POLLIN, 0});
    const size_t first_watch = fds.size();
    // Copy: a handler may unwatch or watch fds while we iterate.
    const std::vector<Watch> watches = watches_;
    for (const auto& w : watches) fds.push_back({w.fd, POLLIN, 0});

    const int n = ::poll(fds.data(), fds.size(), timeout_ms);
    if (n < 0 && errno != EINTR) {
      error("poll", std::string("poll failed: ") + std::strerror(errno));
      break;
    }
    if (n > 0) {
      if (fds[1].revents & POLLIN) {
        signalfd_siginfo si{};
        if (::read(signal_fd_, &si, sizeof si) > 0)
          spdlog::info("signal {} received, stopping", si.ssi_signo);
        stop_ = true;
        break;
      }
      if (fds[0].revents & POLLIN) handle_waiting_messages();
      for (size_t i = 0; i < watches.size(); ++i) {
        if (!(fds[first_watch + i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
        // On "sim", an fd's data (CAN frames, TCP telegrams) is timed with the
        // clock: take in the newest SIM_CLOCK first, or data the simulator sent
        // after a clock tick would be stamped with the tick before.
        if (options_.clock == ClockSource::kSim) handle_waiting_messages();  // takes the clock ticks first
        // Still watched? An earlier callback may have removed it.
        const bool live = std::any_of(watches_.begin(), watches_.end(),
                                      [&](const Watch& w) { return w.id == watches[i].id; });
        if (!live) continue;
        try {
          watches[i].fn();
        } catch (const std::exception& e) {
          error("fd", std::string("fd handler failed: ") + e.what());
        }
      }
    }
    take_clock_ticks();
    fire_due_timers(system_timers_, steady_us());
    // On "sim", once per turn at the newest SIM_CLOCK: a node that fell behind
    // and finds a backlog of clock messages runs each timer once, skipping the
    // missed periods as on the system clock, rather than a burst of them.
    if (!driven_clock_)
      fire_due_timers(timers_, steady_us());
    else if (clock_started_)
      fire_due_timers(timers_, clock_now_us_);
  }
  in_live_loop_ = false;
  shutdown();
}

namespace {

// LCM's reader returns no event both at the end of a log and at bytes that
// are not an event (it says so on stderr at most), so a damaged log would
// replay as a shorter one. It ends a good log at its last byte; anywhere else
// the rest of the file is not events. A file without a single event is no
// LCM log at all, whatever its size (the reader skips bytes looking for one).
class CheckedLogReader {
 public:
  explicit CheckedLogReader(const std::string& path) : path_(path), log_(path, "r") {
    std::error_code ec;
    size_ = std::filesystem::file_size(path, ec);
    if (!log_.good() || ec) throw LogFileError(LogFileError::Kind::kCannotOpen, "cannot read LCM log '" + path + "'");
  }
  const lcm::LogEvent* next() {
    const lcm::LogEvent* ev = log_.readNextEvent();
    FILE* f = log_.getFilePtr();
    if (ev) {
      ++events_;
      // The reader leaves the file at the next event's first byte.
      end_of_events_ = f ? ::ftello(f) : -1;
      return ev;
    }
    if (events_ == 0 && size_ > 0)
      throw LogFileError(LogFileError::Kind::kNotAllEvents,
                         "'" + path_ + "' is not an LCM log: no event in its " + std::to_string(size_) + " bytes");
    const auto at = end_of_events_;
    if (at < 0 || static_cast<std::uintmax_t>(at) < size_)
      throw LogFileError(LogFileError::Kind::kNotAllEvents,
                         "'" + path_ + "': no LCM event at byte " + std::to_string(at) + " of " +
                             std::to_string(size_) + ", after " + std::to_string(events_) +
                             " events (the log is damaged or cut)");
    return nullptr;
  }

 private:
  std::string path_;
  lcm::LogFile log_;
  std::uintmax_t size_ = 0;
  int64_t events_ = 0;
  off_t end_of_events_ = 0;  // the byte after the last whole event
};

}  // namespace

int64_t Node::replay_logs(const std::vector<std::string>& paths) {
  std::vector<std::unique_ptr<CheckedLogReader>> logs;
  for (const auto& path : paths) logs.push_back(std::make_unique<CheckedLogReader>(path));
  if (state_ == pex::daemon_status_t::STATE_STARTING) set_state(pex::daemon_status_t::STATE_OK);
  int64_t events = 0;
  try {
    std::vector<const lcm::LogEvent*> heads;
    for (auto& log : logs) heads.push_back(log->next());
    while (!stop_) {
      // The earliest head; strict < keeps ties in command-line order.
      size_t next = heads.size();
      for (size_t i = 0; i < heads.size(); ++i)
        if (heads[i] && (next == heads.size() || heads[i]->timestamp < heads[next]->timestamp)) next = i;
      if (next == heads.size()) break;
      const lcm::LogEvent* ev = heads[next];
      dispatch(ev->channel, ev->data, ev->datalen, ev->timestamp);
      heads[next] = logs[next]->next();  // invalidates ev
      ++events;
      if (signal_fd_ >= 0 && events % 4096 == 0) {
        pollfd p{signal_fd_, POLLIN, 0};
        if (::poll(&p, 1, 0) > 0) stop_ = true;
      }
    }
  } catch (const LogFileError&) {
    shutdown();  // what was replayed is kept: outputs written, checkpoints saved
    throw;
  }
  shutdown();
  return events;
}

void Node::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  stop_ = true;
  for (auto& hook : shutdown_hooks_) {
    try {
      hook();
    } catch (const std::exception& e) {
      error("shutdown", std::string("shutdown hook failed: ") + e.what());
    }
  }
  state_ = pex::daemon_status_t::STATE_STOPPING;
  publish_status();
  if (!options_.offline) sd_notify(0, "STOPPING=1");
}

}  // namespace pex::runtime
