#include "runtime/node.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <pex/daemon_status_t.hpp>
#include <pex/pose_t.hpp>

#include "runtime/channels.hpp"

using pex::runtime::BadInput;
using pex::runtime::Node;
using pex::runtime::NodeOptions;

namespace {

std::vector<uint8_t> encode(const pex::pose_t& p) {
  std::vector<uint8_t> buf(static_cast<size_t>(p.getEncodedSize()));
  p.encode(buf.data(), 0, static_cast<int>(buf.size()));
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

}  // namespace

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
    if (p.x < 0) throw BadInput("negative x");
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

TEST(Node, ReplayOfSeveralLogsMergesThemByEventTime) {
  const auto dir = std::filesystem::temp_directory_path() / ("pex_node_merge_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  auto write_log = [&](const std::string& name, const std::vector<int64_t>& times, double tag) {
    const std::string path = (dir / name).string();
    lcm::LogFile log(path, "w");
    for (int64_t t : times) {
      const auto buf = encode(pose(t, tag));
      lcm::LogEvent ev{};
      ev.timestamp = t;
      ev.channel = "P";
      ev.datalen = static_cast<int32_t>(buf.size());
      ev.data = const_cast<uint8_t*>(buf.data());
      log.writeEvent(&ev);
    }
    return path;
  };
  const std::string a = write_log("a.lcm", {10, 30, 50}, 1.0);
  const std::string b = write_log("b.lcm", {20, 30, 40, 60}, 2.0);
  Node node(NodeOptions{"t", "", true, "", 1.0});
  std::vector<std::pair<int64_t, double>> seen;
  node.subscribe<pex::pose_t>("P", [&](const pex::pose_t& p) { seen.emplace_back(p.utime, p.x); });
  EXPECT_EQ(node.replay_logs({a, b}), 7);
  const std::vector<std::pair<int64_t, double>> expected = {{10, 1}, {20, 2}, {30, 1}, {30, 2}, {40, 2}, {50, 1}, {60, 2}};
  EXPECT_EQ(seen, expected);
  std::filesystem::remove_all(dir);
}
