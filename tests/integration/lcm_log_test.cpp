// lcm-logger and lcm-logplayer, the real tools, on the daemons' traffic.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "harness.hpp"
#include "runtime/channels.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;

namespace {
struct LoggedEvent {
  std::string channel;
  std::vector<uint8_t> bytes;
};

std::vector<LoggedEvent> read_log(const std::string& path);

// Publishes a DAEMON_STATUS named `name` every 100 ms until lcm-logger has it
// in its file at `path` (a registered type, so the log stays all decodable);
// false after 30 s.
bool logged_marker(Bus& bus, const std::string& path, const std::string& name) {
  pex::daemon_status_t marker{};
  marker.name = name;
  auto in_file = [&] {
    if (!std::filesystem::exists(path)) return false;
    lcm::LogFile log(path, "r");  // a half-written last event just ends the reading
    if (!log.good()) return false;
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      pex::daemon_status_t s{};
      if (ev->channel == pex::runtime::channels::kDaemonStatus && s.decode(ev->data, 0, ev->datalen) == ev->datalen &&
          s.name == name)
        return true;
    }
    return false;
  };
  return bus.spin_until(
      [&] {
        bus.publish(std::string(pex::runtime::channels::kDaemonStatus), marker);
        bus.spin_for(100ms);
        return in_file();
      },
      30s);
}

std::vector<LoggedEvent> read_log(const std::string& path) {
  std::vector<LoggedEvent> out;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  if (!log.good()) return out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.push_back({ev->channel, std::vector<uint8_t>(p, p + ev->datalen)});
  }
  return out;
}
}  // namespace

TEST(LcmLog, RecordsAndReplaysTheHeartbeatsOfARunningSet) {
  const std::string dir = make_temp_dir("lcmlog");
  const std::string log_path = dir + "/set.lcm";
  const std::vector<std::string> daemons = {"explorer", "slam", "polygon_mapper"};

  // Record our channels (LCM's own LCM_SELF_TEST traffic is not ours to keep).
  std::string channels;
  for (const auto& c : pex::runtime::channels::kRegistry) channels += (channels.empty() ? "" : "|") + std::string(c.name);
  {
    Process logger({"/usr/bin/lcm-logger", "-f", "-q", "--channel=" + channels,
                    std::string("--lcm-url=") + kTestLcmUrl, log_path},
                   dir + "/logger.log");
    Bus bus;
    // The logger is listening once a marker of ours is in its file.
    ASSERT_TRUE(logged_marker(bus, log_path, "marker-start")) << logger.output();
    std::vector<std::unique_ptr<Process>> set;
    for (const auto& d : daemons) set.push_back(start_daemon(d, dir));
    EXPECT_TRUE(bus.spin_until([&] {
      for (const auto& d : daemons) {
        auto it = bus.status().find(d);
        if (it == bus.status().end() || it->second.msgs_out < 3) return false;
      }
      return true;
    }, 60s));
    for (auto& p : set) EXPECT_EQ(p->stop(), 0) << p->output();
    // Everything the daemons sent is in the file once a marker sent after it is.
    EXPECT_TRUE(logged_marker(bus, log_path, "marker-end")) << logger.output();
    EXPECT_EQ(logger.stop(), 0) << logger.output();
  }

  // Every event in the log decodes with the generated type the registry names.
  const auto events = read_log(log_path);
  std::map<std::string, int> statuses_by_daemon;
  for (const auto& e : events) {
    EXPECT_EQ(decode_registered(e.channel, e.bytes.data(), static_cast<int>(e.bytes.size())), "");
    if (e.channel == pex::runtime::channels::kDaemonStatus) {
      pex::daemon_status_t s{};
      s.decode(e.bytes.data(), 0, static_cast<int>(e.bytes.size()));
      ++statuses_by_daemon[s.name];
    }
  }
  for (const auto& d : daemons) EXPECT_GE(statuses_by_daemon[d], 3) << d;

  // Replay with lcm-logplayer: the bus sees the same events, byte for byte.
  Bus bus;
  std::vector<LoggedEvent> replayed;
  for (const auto& c : pex::runtime::channels::kRegistry) {
    const std::string ch(c.name);
    bus.lcm().subscribeFunction(
        ch, +[](const lcm::ReceiveBuffer* rb, const std::string& channel, std::vector<LoggedEvent>* out) {
          const auto* p = static_cast<const uint8_t*>(rb->data);
          out->push_back({channel, std::vector<uint8_t>(p, p + rb->data_size)});
        }, &replayed);
  }
  Process player({"/usr/bin/lcm-logplayer", "--speed=4", std::string("--lcm-url=") + kTestLcmUrl, log_path}, dir + "/player.log");
  EXPECT_TRUE(bus.spin_until([&] { return replayed.size() >= events.size(); }, 60s));
  EXPECT_EQ(player.wait(30s), 0) << player.output();
  bus.spin_for(200ms);  // anything beyond the log's events would be here by now: the player has exited
  ASSERT_EQ(replayed.size(), events.size());
  for (size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(replayed[i].channel, events[i].channel) << i;
    EXPECT_EQ(replayed[i].bytes, events[i].bytes) << i;
  }
  std::filesystem::remove_all(dir);
}

// `--log` of a file that is not a whole LCM log ends with an error naming the
// file and the place, and a non-zero exit (65 damaged or foreign, 66 cannot
// open), instead of replaying part of it as if it were all; what was replayed
// before the damage is still written out.
TEST(LcmLog, ReplayOfADamagedForeignOrMissingLogExitsNonZeroNamingIt) {
  const std::string dir = make_temp_dir("damaged-log");
  const std::string readme = source_path("README.md");
  const auto foreign = run_to_completion(
      {bin_path("pex-slam"), "--config", source_path("config/slam.toml"), "--log", readme}, 30s);
  EXPECT_EQ(foreign.exit_code, 65) << foreign.output;
  EXPECT_NE(foreign.output.find("is not an LCM log"), std::string::npos) << foreign.output;
  EXPECT_NE(foreign.output.find(readme), std::string::npos) << foreign.output;

  const auto missing = run_to_completion(
      {bin_path("pex-slam"), "--config", source_path("config/slam.toml"), "--log", dir + "/no-such.lcm"}, 30s);
  EXPECT_EQ(missing.exit_code, 66) << missing.output;

  // A real log (the first 300 scans of the Intel log) with 64 bytes
  // overwritten at two thirds of its length.
  const std::filesystem::path clf = shared_path("data/intel.clf");
  ASSERT_TRUE(std::filesystem::exists(clf)) << clf;
  {
    std::ifstream in(clf);
    std::ofstream out(dir + "/head.clf");
    std::string line;
    for (int scans = 0; scans < 300 && std::getline(in, line);) {
      out << line << '\n';
      if (line.rfind("FLASER ", 0) == 0) ++scans;
    }
  }
  const std::string log = dir + "/head.lcm";
  ASSERT_EQ(run_to_completion({bin_path("pex-carmen2lcm"), dir + "/head.clf", log}).exit_code, 0);
  const auto size = std::filesystem::file_size(log);
  {
    std::fstream f(log, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size * 2 / 3));
    for (int i = 0; i < 64; ++i) f.put(static_cast<char>(0x5A));
  }
  const std::string poses = dir + "/poses.txt";
  const auto damaged = run_to_completion({bin_path("pex-slam"), "--config", source_path("config/slam.toml"), "--log",
                                          log, "--poses", poses},
                                         120s);
  EXPECT_EQ(damaged.exit_code, 65) << damaged.output;
  EXPECT_NE(damaged.output.find("no LCM event at byte"), std::string::npos) << damaged.output;
  // The scans before the damage were processed and their poses written.
  std::ifstream in(poses);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  EXPECT_GT(lines, 100) << damaged.output;
  EXPECT_LT(lines, 300);
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(dir);
}
