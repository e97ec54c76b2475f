// Bad input on the bus: bytes that are not the channel's type, and messages
// that decode but carry nonsense (NaN, sizes that disagree, indices out of
// range). Every daemon must count them as rejected, keep running, and stay
// healthy; the base driver refuses a NaN velocity command like the garbage.
// Small packets claiming huge or negative array counts and string lengths
// (issue 12) are rejected too, without costing memory.
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>

#include <pex/laser_scan_t.hpp>
#include <pex/mission_cmd_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_fault_t.hpp>
#include <pex/slam_update_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include "harness.hpp"
#include "runtime/channels.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;
namespace ch = pex::runtime::channels;

TEST(BadInput, EveryDaemonCountsRejectsAndKeepsRunning) {
  Bus bus;
  const std::string logs = make_temp_dir("badinput");
  std::vector<std::unique_ptr<Process>> set;
  set.push_back(start_daemon("sim", logs));
  const std::vector<std::string> daemons = {"base_driver", "slam", "polygon_mapper", "explorer"};
  for (const auto& d : daemons) set.push_back(start_daemon(d, logs));
  std::vector<std::string> all = daemons;
  all.push_back("sim");
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok(all); }, 5s));
  std::map<std::string, int64_t> rejected_before;
  for (const auto& d : daemons) rejected_before[d] = bus.status().at(d).msgs_rejected;

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<uint8_t> garbage = {0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  for (const auto& c : {ch::kLidarScan, ch::kOdometry, ch::kSlamUpdate, ch::kMap, ch::kSlamPose, ch::kBaseCmd})
    bus.lcm().publish(std::string(c), garbage.data(), static_cast<unsigned>(garbage.size()));

  pex::laser_scan_t scan{};  // angles NaN: no sensor geometry to build anything from
  scan.utime = 1;
  scan.angle_min = static_cast<float>(nan);
  scan.angle_increment = static_cast<float>(nan);
  scan.range_max = 20;
  scan.nranges = 3;
  scan.ranges = {1, 2, 3};
  bus.publish(std::string(ch::kLidarScan), scan);

  pex::slam_update_t update{};  // best particle out of range
  update.utime = 2;
  update.best = 7;
  update.nparticles = 1;
  update.particles.resize(1);
  bus.publish(std::string(ch::kSlamUpdate), update);

  pex::polygon_map_t map{};  // a ring whose edge types disagree with its vertices
  map.utime = 3;
  map.nrings = 1;
  map.rings.resize(1);
  map.rings[0].nvertices = 3;
  map.rings[0].x = {0, 1, nan};
  map.rings[0].y = {0, 0, 1};
  map.rings[0].edge_type = {0, 0, 0};
  bus.publish(std::string(ch::kMap), map);

  pex::velocity_cmd_t cmd{};
  cmd.utime = 4;
  cmd.v = nan;
  cmd.omega = 0;
  cmd.source = "test";
  bus.publish(std::string(ch::kBaseCmd), cmd);

  // Every daemon heard at least the garbage on its channels and refused it.
  const std::map<std::string, int> expected_at_least = {
      {"base_driver", 2}, {"slam", 2}, {"polygon_mapper", 3}, {"explorer", 2}};
  const bool all_counted = bus.spin_until([&] {
    for (const auto& [d, n] : expected_at_least)
      if (bus.status().at(d).msgs_rejected - rejected_before[d] < n) return false;
    return true;
  }, 5s);
  std::string report;
  for (const auto& d : daemons)
    report += d + ": rejected " + std::to_string(bus.status().at(d).msgs_rejected - rejected_before[d]) + ", last '" +
              bus.status().at(d).last_error + "'\n";
  EXPECT_TRUE(all_counted) << report;

  // Still alive, still healthy, still heartbeating.
  for (auto& p : set) EXPECT_TRUE(p->running()) << p->name() << "\n" << p->output();
  std::map<std::string, int64_t> out_before;
  for (const auto& d : daemons) out_before[d] = bus.status().at(d).msgs_out;
  bus.spin_for(2200ms);
  for (const auto& d : daemons) {
    EXPECT_GT(bus.status().at(d).msgs_out, out_before[d]) << d;
    EXPECT_NE(bus.status().at(d).state, +pex::daemon_status_t::STATE_ERROR) << d;
  }
  for (auto& p : set) EXPECT_EQ(p->stop(), 0) << p->name() << "\n" << p->output();
  std::filesystem::remove_all(logs);
}

namespace {

// Peak resident memory of a process (VmHWM), in kB; -1 if unreadable.
int64_t peak_rss_kb(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  while (status >> key) {
    if (key == "VmHWM:") {
      int64_t kb = -1;
      status >> kb;
      return kb;
    }
    status.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return -1;
}

// `msg` encoded (its arrays and strings empty) with the int32 that ends
// `from_end` bytes before the end of the encoding set to `value`, padded with
// zeros to the 173 bytes.
template <class Msg>
std::vector<uint8_t> with_int32_from_end(const Msg& msg, size_t from_end, int32_t value) {
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const size_t at = bytes.size() - from_end;
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<uint8_t>(static_cast<uint32_t>(value) >> (24 - 8 * i));
  bytes.resize(std::max<size_t>(bytes.size(), 173), 0);
  return bytes;
}

}  // namespace

// Issue 12: a 173-byte packet made the explorer allocate 870 MB, and negative
// counts were counted as the daemon's errors. Every daemon gets packets whose
// count fields claim far more elements than their bytes hold, or fewer than
// none, on each channel it decodes; it must count each as rejected, keep
// running and healthy, and its peak memory must not grow by 50 MB.
//
// The counts are picked so that an unbounded decoder would touch 134 MB
// (2^25 floats) to 185 MB (2^21 rings) per packet, above the 50 MB, without
// paging in gigabytes on the test machine; INT32_MAX is sent only where
// lcm-gen's decoder would ask for more than any machine grants (86 GB of
// particles, 189 GB of rings) and fail at once.
TEST(BadInput, HostileCountsAreRejectedWithoutCostingMemory) {
  Bus bus;
  const std::string logs = make_temp_dir("hostilecounts");
  std::map<std::string, std::unique_ptr<Process>> set;
  const std::vector<std::string> daemons = {"sim", "base_driver", "slam", "polygon_mapper", "explorer"};
  for (const auto& d : daemons) set[d] = start_daemon(d, logs);
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok(daemons); }, 5s)) << logs_of({set["sim"].get()});
  std::map<std::string, int64_t> rejected_before, peak_before_kb;
  for (const auto& d : daemons) {
    rejected_before[d] = bus.status().at(d).msgs_rejected;
    peak_before_kb[d] = peak_rss_kb(set[d]->pid());
    ASSERT_GT(peak_before_kb[d], 0) << d;
  }

  struct Hostile {
    std::string channel;
    std::vector<uint8_t> bytes;
  };
  std::vector<Hostile> packets;
  const pex::laser_scan_t scan{};       // ... nranges, nintensities: its last 8 bytes
  for (const int32_t n : {1 << 25, -1, INT32_MIN}) {
    packets.push_back({std::string(ch::kLidarScan), with_int32_from_end(scan, 8, n)});
    packets.push_back({std::string(ch::kLidarScan), with_int32_from_end(scan, 4, n)});
  }
  const pex::slam_update_t update{};    // ... nparticles: its last 4 bytes
  const pex::polygon_map_t map{};       // ... nrings: its last 4 bytes
  for (const int32_t n : {1 << 22, INT32_MAX, -1, INT32_MIN})
    packets.push_back({std::string(ch::kSlamUpdate), with_int32_from_end(update, 4, n)});
  for (const int32_t n : {1 << 21, INT32_MAX, -1, INT32_MIN})
    packets.push_back({std::string(ch::kMap), with_int32_from_end(map, 4, n)});
  // String lengths: lcm-gen copied length - 1 bytes, so 0 and negative
  // lengths asked std::string for 2^64 - 1 or wrapped around.
  pex::velocity_cmd_t cmd{};            // ... source: its last 5 bytes ("" is length 1 and a NUL)
  pex::mission_cmd_t mission{};
  pex::sim_fault_t fault{};
  for (const int32_t n : {0, -1, INT32_MIN}) {
    packets.push_back({std::string(ch::kBaseCmd), with_int32_from_end(cmd, 5, n)});
    packets.push_back({std::string(ch::kMissionCmd), with_int32_from_end(mission, 5, n)});
    packets.push_back({std::string(ch::kSimFault), with_int32_from_end(fault, 5, n)});
  }
  // Who decodes which channel (configs in config/: the mapper on SLAM, the
  // explorer on SLAM_POSE).
  const std::map<std::string, std::vector<std::string>> decodes = {
      {"sim", {std::string(ch::kSimFault)}},
      {"base_driver", {std::string(ch::kBaseCmd)}},
      {"slam", {std::string(ch::kLidarScan)}},
      {"polygon_mapper", {std::string(ch::kLidarScan), std::string(ch::kSlamUpdate)}},
      {"explorer", {std::string(ch::kLidarScan), std::string(ch::kMap), std::string(ch::kMissionCmd)}},
  };
  constexpr int kRounds = 2;
  std::map<std::string, int64_t> expected;
  for (int round = 0; round < kRounds; ++round) {
    for (const auto& p : packets) {
      bus.lcm().publish(p.channel, p.bytes.data(), static_cast<unsigned>(p.bytes.size()));
      for (const auto& [d, channels] : decodes)
        if (std::find(channels.begin(), channels.end(), p.channel) != channels.end()) ++expected[d];
      bus.spin_for(20ms);  // paced like a device: the test is about memory, not socket buffers
    }
  }

  auto rejected = [&](const std::string& d) { return bus.status().at(d).msgs_rejected - rejected_before[d]; };
  const bool all_counted = bus.spin_until([&] {
    for (const auto& [d, n] : expected)
      if (rejected(d) < n) return false;
    return true;
  }, 5s);
  std::string report;
  for (const auto& d : daemons) {
    const int64_t peak_kb = peak_rss_kb(set[d]->pid());
    report += d + ": rejected " + std::to_string(rejected(d)) + " of " + std::to_string(expected[d]) +
              ", peak RSS " + std::to_string(peak_before_kb[d]) + " -> " + std::to_string(peak_kb) + " kB, last '" +
              bus.status().at(d).last_error + "'\n";
    EXPECT_LT(peak_kb - peak_before_kb[d], 50 * 1024) << d;
  }
  std::cout << packets.size() * kRounds << " hostile packets of 173 bytes:\n" << report;
  EXPECT_TRUE(all_counted) << report;

  // Still alive, healthy and heartbeating.
  std::map<std::string, int64_t> out_before;
  for (const auto& d : daemons) out_before[d] = bus.status().at(d).msgs_out;
  bus.spin_for(2200ms);
  for (const auto& d : daemons) {
    EXPECT_TRUE(set[d]->running()) << d << "\n" << set[d]->output();
    EXPECT_GT(bus.status().at(d).msgs_out, out_before[d]) << d;
    EXPECT_NE(bus.status().at(d).state, +pex::daemon_status_t::STATE_ERROR) << d;
  }
  for (auto& [d, p] : set) EXPECT_EQ(p->stop(), 0) << d << "\n" << p->output();
  std::filesystem::remove_all(logs);
}
