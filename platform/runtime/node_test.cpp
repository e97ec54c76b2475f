#include "runtime/node.hpp"
#include "runtime/run_guarded.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <cmath>
#include <sstream>
#include <memory>
#include <stdexcept>
#include <pex/daemon_status_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>

#include "runtime/log_capture.hpp"
#include "runtime/log_file_error.hpp"
#include "runtime/channels.hpp"


using pex::runtime::ClockSource;
using pex::runtime::LogCapture;
using pex::runtime::LogFileError;
using pex::runtime::Node;
using pex::runtime::NodeOptions;
using pex::daemon_status_t;
namespace ch = pex::runtime::channels;

namespace {

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

pex::pose_t pose(int64_t utime, double x) {
  pex::pose_t p{};
  p.utime = utime;
  p.x = x;
  p.y = 0;
  p.theta = 0;
  return p;
}

// A component's counters, as show_counters takes them.
struct ShownCounters {
  int64_t refused = 0;  // an event
  int64_t held = 0;     // a total
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    v.event("refused", refused);
    v.total("held", held);
  }
};

}  // namespace

// An input watch's reason counts the time ("no SLAM_UPDATE for 3.4 s"), so
// it changes at every check while the input is away: each change of state is
// a log line, the same state with a new reason one line in 10 s at most
// (held back, counted); the systemd status line has the newest reason.
TEST(Node, AStateIsLoggedWhenItChangesNotAtEveryNewCountOfItsReason) {
  const LogCapture log;
  {
    Node node(NodeOptions{"t", "", true, "", 1.0});
    node.set_state(daemon_status_t::STATE_OK);
    for (int tenths = 31; tenths < 231; ++tenths)  // 20 s of checks four times a second, in a test's microseconds
      node.set_state(daemon_status_t::STATE_DEGRADED, "no SLAM_UPDATE for " + std::to_string(tenths / 10) + "." +
                                                          std::to_string(tenths % 10) + " s");
    EXPECT_EQ(log.lines_with("state DEGRADED: no SLAM_UPDATE for 3.1 s"), 1) << log.text();
    EXPECT_EQ(log.lines_with("state DEGRADED"), 1) << log.text();
    EXPECT_EQ(node.published_state(), static_cast<int8_t>(daemon_status_t::STATE_DEGRADED));
    node.set_state(daemon_status_t::STATE_OK);
    node.set_state(daemon_status_t::STATE_DEGRADED, "no LIDAR_SCAN for 3.0 s");
    node.set_state(daemon_status_t::STATE_ERROR, "no LIDAR_SCAN for 3.5 s");
    EXPECT_EQ(log.lines_with("state OK"), 2) << log.text();
    EXPECT_EQ(log.lines_with("state DEGRADED: no LIDAR_SCAN for 3.0 s"), 1) << log.text();
    EXPECT_EQ(log.lines_with("state ERROR: no LIDAR_SCAN for 3.5 s"), 1) << log.text();
  }
}

TEST(Node, DispatchDecodesAndCallsHandler) {
  Node node(NodeOptions{"t", "", true, "", 1.0});
  std::vector<double> xs;
  node.subscribe<pex::pose_t>("P", [&](const pex::pose_t& p) { xs.push_back(p.x); });
  const auto buf = encode(pose(1, 2.5));
  node.dispatch("P", buf.data(), static_cast<int>(buf.size()), 1);
  node.dispatch("OTHER", buf.data(), static_cast<int>(buf.size()), 2);
  EXPECT_EQ(xs, std::vector<double>{2.5});
  EXPECT_EQ(node.msgs_rejected(), 0);
}

TEST(Node, ShowCountersShowsTotalsAlwaysAndEventsOnceTheyHaveCounted) {
  ShownCounters c;
  Node node(NodeOptions{"t", "", true, "", 1.0});
  node.show_counters(c);
  EXPECT_EQ(node.counters().count("refused"), 0u);
  ASSERT_EQ(node.counters().count("held"), 1u);
  EXPECT_EQ(node.counters().at("held"), 0);
  c.refused = 2;
  c.held = 5;
  node.show_counters(c);
  ASSERT_EQ(node.counters().count("refused"), 1u);
  EXPECT_EQ(node.counters().at("refused"), 2);
  EXPECT_EQ(node.counters().at("held"), 5);
}

TEST(Node, CollectedCountersAreReadWithoutBeingShownByHand) {
  auto c = std::make_shared<ShownCounters>();
  Node node(NodeOptions{"t", "", true, "", 1.0});
  node.collect_counters([c]() -> const ShownCounters& { return *c; });
  // A handler that counts a refusal in its component and refuses the message:
  // nothing in it shows the counters, the node reads them when it reports.
  node.subscribe<pex::pose_t>("P", [c](const pex::pose_t& p) {
    c->held = static_cast<int64_t>(std::abs(p.x));
    if (p.x < 0) {
      ++c->refused;
      throw std::invalid_argument("negative x");
    }
  });
  const auto good = encode(pose(1, 7.0));
  node.dispatch("P", good.data(), static_cast<int>(good.size()), 1);
  EXPECT_EQ(node.counters().at("held"), 7);
  EXPECT_EQ(node.counters().count("refused"), 0u);
  const auto bad = encode(pose(2, -9.0));
  node.dispatch("P", bad.data(), static_cast<int>(bad.size()), 2);
  EXPECT_EQ(node.msgs_rejected(), 1);
  EXPECT_EQ(node.errors(), 1);
  EXPECT_EQ(node.counters().at("held"), 9);
  ASSERT_EQ(node.counters().count("refused"), 1u);
  EXPECT_EQ(node.counters().at("refused"), 1);
}

TEST(Node, MalformedBytesAreCountedAndDropped) {
  Node node(NodeOptions{"t", "", true, "", 1.0});
  int calls = 0;
  node.subscribe<pex::pose_t>("P", [&](const pex::pose_t&) { ++calls; });
  auto buf = encode(pose(1, 2.5));
  node.dispatch("P", buf.data(), 5, 1);                            // truncated
  std::vector<uint8_t> garbage(buf.size(), 0xAB);                  // wrong fingerprint
  node.dispatch("P", garbage.data(), static_cast<int>(garbage.size()), 2);
  buf.push_back(0);                                                // trailing byte
  node.dispatch("P", buf.data(), static_cast<int>(buf.size()), 3);
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(node.msgs_rejected(), 3);
  const auto good = encode(pose(4, 1.0));
  node.dispatch("P", good.data(), static_cast<int>(good.size()), 4);
  EXPECT_EQ(calls, 1);  // still working after bad input
}

TEST(Node, HandlerExceptionsAreSurvived) {
  Node node(NodeOptions{"t", "", true, "", 1.0});
  node.subscribe<pex::pose_t>("P", [&](const pex::pose_t& p) {
    if (p.x < 0) throw std::invalid_argument("negative x");
    if (p.x > 100) throw std::runtime_error("internal");
  });
  const auto bad = encode(pose(1, -1));
  const auto boom = encode(pose(2, 101));
  node.dispatch("P", bad.data(), static_cast<int>(bad.size()), 1);
  node.dispatch("P", boom.data(), static_cast<int>(boom.size()), 2);
  EXPECT_EQ(node.msgs_rejected(), 1);
  EXPECT_EQ(node.errors(), 2);
}

TEST(Node, OfflineTimersFollowEventTime) {
  Node node(NodeOptions{"t", "", true, "", 1.0});
  std::vector<int64_t> fired;
  node.every(std::chrono::milliseconds(100), [&](int64_t now) { fired.push_back(now); });
  node.subscribe<pex::pose_t>("P", [](const pex::pose_t&) {});
  const auto buf = encode(pose(0, 0));
  // Events every 30 ms of log time over 1 s: the 100 ms timer fires about 10 times,
  // regardless of how fast the loop runs.
  for (int64_t t = 1'000'000; t <= 2'000'000; t += 30'000)
    node.dispatch("P", buf.data(), static_cast<int>(buf.size()), t);
  ASSERT_GE(fired.size(), 9u);
  ASSERT_LE(fired.size(), 10u);
  for (size_t i = 1; i < fired.size(); ++i) EXPECT_GE(fired[i] - fired[i - 1], 90'000);
}

TEST(Node, OfflineOutputLogHoldsPublishedMessages) {
  const auto dir = std::filesystem::temp_directory_path() / ("pex_node_test_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "out.lcm").string();
  {
    Node node(NodeOptions{"t", "", true, path, 1.0});
    node.subscribe<pex::pose_t>("IN", [&](const pex::pose_t& p) {
      auto q = p;
      q.x *= 2;
      node.publish("OUT", q);
    });
    for (int i = 0; i < 3; ++i) {
      const auto buf = encode(pose(i, i));
      node.dispatch("IN", buf.data(), static_cast<int>(buf.size()), 1'000'000 + i);
    }
    node.shutdown();
  }
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  std::vector<double> xs;
  int statuses = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == "OUT") {
      pex::pose_t p{};
      ASSERT_EQ(p.decode(ev->data, 0, ev->datalen), ev->datalen);
      xs.push_back(p.x);
    } else if (ev->channel == pex::runtime::channels::kDaemonStatus) {
      pex::daemon_status_t s{};
      ASSERT_EQ(s.decode(ev->data, 0, ev->datalen), ev->datalen);
      EXPECT_EQ(s.name, "t");
      ++statuses;
    }
  }
  EXPECT_EQ(xs, (std::vector<double>{0, 2, 4}));
  EXPECT_GE(statuses, 1);  // the final STOPPING status at least
  std::filesystem::remove_all(dir);
}

namespace {

// A log of pose events on channel P, one at each of `times` (utime and
// event time), x = `tag`.
std::string write_pose_log(const std::filesystem::path& path, const std::vector<int64_t>& times, double tag = 0.0) {
  lcm::LogFile log(path.string(), "w");
  for (int64_t t : times) {
    const auto buf = encode(pose(t, tag));
    lcm::LogEvent ev{};
    ev.timestamp = t;
    ev.channel = "P";
    ev.datalen = static_cast<int32_t>(buf.size());
    ev.data = const_cast<uint8_t*>(buf.data());
    log.writeEvent(&ev);
  }
  return path.string();
}

// 0, 1, ..., n - 1.
std::vector<int64_t> first_times(int n) {
  std::vector<int64_t> times(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) times[static_cast<std::size_t>(i)] = i;
  return times;
}

}  // namespace

TEST(Node, ReplayOfSeveralLogsMergesThemByEventTime) {
  const auto dir = std::filesystem::temp_directory_path() / ("pex_node_merge_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string a = write_pose_log(dir / "a.lcm", {10, 30, 50}, 1.0);
  const std::string b = write_pose_log(dir / "b.lcm", {20, 30, 40, 60}, 2.0);
  Node node(NodeOptions{"t", "", true, "", 1.0});
  std::vector<std::pair<int64_t, double>> seen;
  node.subscribe<pex::pose_t>("P", [&](const pex::pose_t& p) { seen.emplace_back(p.utime, p.x); });
  EXPECT_EQ(node.replay_logs({a, b}), 7);
  const std::vector<std::pair<int64_t, double>> expected = {{10, 1}, {20, 2}, {30, 1}, {30, 2}, {40, 2}, {50, 1}, {60, 2}};
  EXPECT_EQ(seen, expected);
  std::filesystem::remove_all(dir);
}


TEST(Node, ReplayOfADamagedLogSaysWhereAndKeepsWhatCameBefore) {
  const auto dir = std::filesystem::temp_directory_path() / ("pex_node_damaged_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = write_pose_log(dir / "d.lcm", first_times(100));
  const auto size = std::filesystem::file_size(path);
  {  // 16 bytes flipped in the middle of the file
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    for (int i = 0; i < 16; ++i) f.put(static_cast<char>(0xA5));
  }
  Node node(NodeOptions{"t", "", true, "", 1.0});
  int seen = 0;
  node.subscribe<pex::pose_t>("P", [&](const pex::pose_t&) { ++seen; });
  try {
    node.replay_log(path);
    FAIL() << "a damaged log replayed as a complete one";
  } catch (const LogFileError& e) {
    EXPECT_EQ(e.kind(), LogFileError::Kind::kNotAllEvents);
    EXPECT_NE(std::string(e.what()).find("no LCM event at byte"), std::string::npos) << e.what();
  }
  EXPECT_GT(seen, 30);   // the events before the damage were handled
  EXPECT_LT(seen, 100);
  EXPECT_TRUE(node.stopping());
  // A log cut short in its last event: the same.
  const std::string cut = write_pose_log(dir / "c.lcm", first_times(10));
  std::filesystem::resize_file(cut, std::filesystem::file_size(cut) - 5);
  Node node2(NodeOptions{"t", "", true, "", 1.0});
  EXPECT_THROW(node2.replay_log(cut), LogFileError);
  // The complete log replays to its end.
  Node node3(NodeOptions{"t", "", true, "", 1.0});
  EXPECT_EQ(node3.replay_log(write_pose_log(dir / "ok.lcm", first_times(10))), 10);
  std::filesystem::remove_all(dir);
}

TEST(Node, ReplayRefusesAForeignFileAndAMissingOne) {
  const auto dir = std::filesystem::temp_directory_path() / ("pex_node_foreign_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string text = (dir / "notes.txt").string();
  std::ofstream(text) << "# not a log\nsome text that is no LCM event at all\n";
  Node node(NodeOptions{"t", "", true, "", 1.0});
  try {
    node.replay_log(text);
    FAIL() << "a text file replayed as an empty log";
  } catch (const LogFileError& e) {
    EXPECT_EQ(e.kind(), LogFileError::Kind::kNotAllEvents);
    EXPECT_NE(std::string(e.what()).find("is not an LCM log"), std::string::npos) << e.what();
  }
  Node node2(NodeOptions{"t", "", true, "", 1.0});
  try {
    node2.replay_log((dir / "missing.lcm").string());
    FAIL() << "a missing log replayed";
  } catch (const LogFileError& e) {
    EXPECT_EQ(e.kind(), LogFileError::Kind::kCannotOpen);
  }
  // An empty file is an empty log (lcm-logger before its first message).
  const std::string empty = (dir / "empty.lcm").string();
  std::ofstream(empty).close();
  Node node3(NodeOptions{"t", "", true, "", 1.0});
  EXPECT_EQ(node3.replay_log(empty), 0);
  std::filesystem::remove_all(dir);
}

// ------------------------------------------------------------- clock = "sim" --

namespace {

constexpr int64_t kSimEpoch = 1'700'000'000'000'000;  // the sim's start, us since the epoch

pex::sim_clock_t sim_clock(int64_t sim_time_us) {
  pex::sim_clock_t c{};
  c.utime = kSimEpoch + sim_time_us;
  c.sim_time_us = sim_time_us;
  c.speed_factor = 10.0;
  return c;
}

// A live node on the simulator's clock. memq:// is LCM's in-process queue: no
// network, and what the node publishes comes back to its own subscriptions.
NodeOptions sim_node_options(double heartbeat_period_s = 1.0) {
  NodeOptions o{"t", "memq://", false, "", heartbeat_period_s};
  o.clock = ClockSource::kSim;
  return o;
}

void dispatch_clock(Node& node, const pex::sim_clock_t& c) {
  const auto buf = encode(c);
  // The receive time is wall time: the node must take its time from the content.
  node.dispatch(ch::kSimClock, buf.data(), static_cast<int>(buf.size()), 42);
}

int64_t counter(const daemon_status_t& s, const std::string& name) {
  for (int i = 0; i < s.ncounters; ++i)
    if (s.counter_names[static_cast<size_t>(i)] == name) return s.counter_values[static_cast<size_t>(i)];
  return -1;
}

}  // namespace

TEST(NodeSimClock, TimersFireInSimulatedTimeOnlyOnceTheClockRuns) {
  Node node(sim_node_options());
  node.set_state(daemon_status_t::STATE_OK);
  std::vector<int64_t> fired;
  node.every(std::chrono::milliseconds(100), [&](int64_t now) { fired.push_back(now); });
  node.subscribe<pex::pose_t>("P", [](const pex::pose_t&) {});

  // Before the first SIM_CLOCK: no time, no timers, and the daemon says why.
  const auto pose_bytes = encode(pose(0, 0));
  for (int64_t wall = 1; wall <= 3; ++wall)
    node.dispatch("P", pose_bytes.data(), static_cast<int>(pose_bytes.size()), wall * 1'000'000);
  EXPECT_TRUE(fired.empty());
  EXPECT_FALSE(node.clock_started());
  EXPECT_EQ(node.now_utime(), 0);
  EXPECT_EQ(node.published_state(), +daemon_status_t::STATE_DEGRADED);
  EXPECT_EQ(node.counter("sim_clock_waiting"), 1);

  // 1 s of simulated time in 10 ms steps: the 100 ms timer fires about ten
  // times, each time with the simulated time it fired at.
  for (int64_t t = 0; t <= 1'000'000; t += 10'000) dispatch_clock(node, sim_clock(t));
  EXPECT_TRUE(node.clock_started());
  EXPECT_EQ(node.now_utime(), kSimEpoch + 1'000'000);
  EXPECT_EQ(node.monotonic_us(), kSimEpoch + 1'000'000);
  EXPECT_EQ(node.published_state(), +daemon_status_t::STATE_OK);
  EXPECT_EQ(node.counter("sim_clock_waiting"), 0);
  ASSERT_EQ(fired.size(), 10u);
  for (size_t i = 0; i < fired.size(); ++i) EXPECT_EQ(fired[i], kSimEpoch + 100'000 * static_cast<int64_t>(i + 1));

  // Other traffic does not move the clock: simulated time stands still.
  for (int64_t wall = 4; wall <= 10; ++wall)
    node.dispatch("P", pose_bytes.data(), static_cast<int>(pose_bytes.size()), wall * 1'000'000);
  EXPECT_EQ(fired.size(), 10u);
  EXPECT_EQ(node.now_utime(), kSimEpoch + 1'000'000);
}

TEST(NodeSimClock, BackwardsOrGarbageClockIsRejectedAndTheLastGoodTimeKept) {
  Node node(sim_node_options());
  int fired = 0;
  node.every(std::chrono::milliseconds(10), [&](int64_t) { ++fired; });
  dispatch_clock(node, sim_clock(2'000'000));
  ASSERT_EQ(node.now_utime(), kSimEpoch + 2'000'000);

  dispatch_clock(node, sim_clock(1'990'000));  // backwards
  auto nan_speed = sim_clock(2'100'000);
  nan_speed.speed_factor = std::nan("");
  dispatch_clock(node, nan_speed);
  auto negative = sim_clock(2'100'000);
  negative.sim_time_us = -5;
  dispatch_clock(node, negative);
  const std::vector<uint8_t> garbage(40, 0xAB);
  node.dispatch(ch::kSimClock, garbage.data(), static_cast<int>(garbage.size()), 42);

  EXPECT_EQ(node.now_utime(), kSimEpoch + 2'000'000);
  EXPECT_EQ(node.counter("sim_clock_rejected"), 4);
  EXPECT_EQ(node.msgs_rejected(), 4);
  EXPECT_EQ(fired, 0);

  // A good clock after the bad ones moves time on as before.
  dispatch_clock(node, sim_clock(2'010'000));
  EXPECT_EQ(node.now_utime(), kSimEpoch + 2'010'000);
  EXPECT_EQ(fired, 1);
}

// The heartbeat runs on the monotonic clock through the live loop: statuses
// flow before the simulator's clock exists (DEGRADED, waiting), turn OK when it
// arrives, and turn ERROR once it has been silent for sim_clock_silence_s.
TEST(NodeSimClock, HeartbeatIsPublishedWithoutTheClockAndReportsIt) {
  NodeOptions options = sim_node_options(0.01);
  options.sim_clock_silence_s = 0.3;  // long enough for the three clock steps below on a loaded host
  Node node(options);
  int user_timer = 0;
  node.every(std::chrono::milliseconds(1), [&](int64_t) { ++user_timer; });
  std::vector<daemon_status_t> statuses;
  int timer_before_clock = -1;
  int timer_after_one_step = -1;
  int ok_statuses = 0;
  node.subscribe<daemon_status_t>(ch::kDaemonStatus, [&](const daemon_status_t& s) {
    statuses.push_back(s);
    // Through the bus, as the simulator sends it. The first OK status comes in
    // the turn of the loop that handled the first clock; later ones are
    // heartbeats, published at the end of a turn and so handled in a later one.
    if (statuses.size() == 3) {
      timer_before_clock = user_timer;
      node.publish(ch::kSimClock, sim_clock(0));
    }
    if (s.state == daemon_status_t::STATE_OK && ++ok_statuses == 2) {
      node.publish(ch::kSimClock, sim_clock(5'000));
    } else if (s.state == daemon_status_t::STATE_OK && ok_statuses == 3) {
      timer_after_one_step = user_timer;
      // A backlog of ten clock messages, as a node that fell behind finds them:
      // handled in one turn, the timer runs once at the newest time.
      for (int64_t t = 10'000; t <= 100'000; t += 10'000) node.publish(ch::kSimClock, sim_clock(t));
    }
    // Enough heartbeats have passed, however slow the machine, or the clock went silent.
    if (statuses.size() >= 1000 || s.state == daemon_status_t::STATE_ERROR) node.request_stop();
  });
  pex::runtime::run_guarded(node);  // until the state above is reached

  ASSERT_GE(statuses.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(statuses[i].state, +daemon_status_t::STATE_DEGRADED) << i;
    EXPECT_EQ(counter(statuses[i], "sim_clock_waiting"), 1) << i;
  }
  EXPECT_EQ(timer_before_clock, 0);
  EXPECT_EQ(timer_after_one_step, 1);  // 5 ms of simulated time: missed periods skipped
  EXPECT_EQ(user_timer, 2);            // the backlog: once, not ten times
  const auto ok = std::find_if(statuses.begin() + 3, statuses.end(),
                               [](const daemon_status_t& s) { return s.state == daemon_status_t::STATE_OK; });
  ASSERT_NE(ok, statuses.end()) << "never OK once SIM_CLOCK ran";
  EXPECT_EQ(counter(*ok, "sim_clock_waiting"), 0);
  EXPECT_EQ(statuses.back().state, +daemon_status_t::STATE_ERROR) << "a silent clock went unnoticed";
  EXPECT_EQ(counter(statuses.back(), "sim_clock_waiting"), 1);
  EXPECT_EQ(node.now_utime(), kSimEpoch + 100'000);
}

TEST(NodeSystemClock, StampsAreWallTimeAndTimeoutsMonotonic) {
  Node node(NodeOptions{"t", "memq://", false, "", 1.0});
  EXPECT_TRUE(node.clock_started());
  const auto wall = std::chrono::duration_cast<std::chrono::microseconds>(
                        std::chrono::system_clock::now().time_since_epoch()).count();
  const auto steady = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::steady_clock::now().time_since_epoch()).count();
  // Each within a minute of its own clock (the two clocks are decades apart).
  EXPECT_NEAR(static_cast<double>(node.now_utime()), static_cast<double>(wall), 60e6);
  EXPECT_NEAR(static_cast<double>(node.monotonic_us()), static_cast<double>(steady), 60e6);
  // SIM_CLOCK means nothing to a node on the system clock.
  dispatch_clock(node, sim_clock(1'000'000));
  EXPECT_NE(node.now_utime(), kSimEpoch + 1'000'000);
}
