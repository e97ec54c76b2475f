// lcm-logger and lcm-logplayer, the real tools, on the daemons' traffic.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>

#include "harness.hpp"
#include "runtime/channels.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;

namespace {
struct LoggedEvent {
  std::string channel;
  std::vector<uint8_t> bytes;
};

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
    std::this_thread::sleep_for(300ms);  // let the logger subscribe first
    std::vector<std::unique_ptr<Process>> set;
    for (const auto& d : daemons) set.push_back(start_daemon(d, dir));
    Bus bus;
    bus.spin_until([&] {
      for (const auto& d : daemons) {
        auto it = bus.status().find(d);
        if (it == bus.status().end() || it->second.msgs_out < 3) return false;
      }
      return true;
    }, 6s);
    for (auto& p : set) EXPECT_EQ(p->stop(), 0) << p->output();
    std::this_thread::sleep_for(300ms);  // the logger flushes every 100 ms
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
  bus.spin_until([&] { return replayed.size() >= events.size(); }, 15s);
  bus.spin_for(200ms);
  EXPECT_EQ(player.wait(5s), 0) << player.output();
  ASSERT_EQ(replayed.size(), events.size());
  for (size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(replayed[i].channel, events[i].channel) << i;
    EXPECT_EQ(replayed[i].bytes, events[i].bytes) << i;
  }
  std::filesystem::remove_all(dir);
}
