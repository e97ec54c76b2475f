// Bad input on the bus: bytes that are not the channel's type, and messages
// that decode but carry nonsense (NaN, sizes that disagree, indices out of
// range). Every daemon must count them as rejected, keep running, and stay
// healthy; the base driver refuses a NaN velocity command like the garbage.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <pex/laser_scan_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
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
