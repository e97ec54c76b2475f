// Fault injection on pex-slam (ctest label `faults`): real daemons on a real
// LCM bus in a private network namespace, checked against the simulator's
// truth (SIM_TRUTH) on the simulated clock (SIM_CLOCK).
//
//   kill -9 pex-slam mid-mission (the set on SLAM, as on the robot) and
//   restart: the restarted SLAM takes its filter up from its checkpoint
//   (particles, maps, trajectories, generator, odometry frame; written every
//   checkpoint_period_s) and goes on from there with the odometry of the same
//   base driver. Its first pose is where the robot is (no jump: SLAM's motion
//   over the restart is the truth's within a few cm), its updates carry the
//   same epoch (the mapper keeps its maps: no epoch change, at most a resync
//   for the updates made after the last checkpoint), and the mission ends
//   DONE with the world mapped and nothing beyond it. Without the checkpoint
//   the restarted SLAM is a new filter: a new epoch, and the mapper drops
//   its maps.
//
//   A robot creeping (SLAM_UPDATE only every 0.5 m) keeps the mapper OK: it
//   knows SLAM is there by SLAM_POSE; SLAM killed, the mapper says so, and
//   is OK again once SLAM is back.
#include <gtest/gtest.h>

#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/slam_update_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "exploration_set.hpp"
#include "geometry/pose2.hpp"
#include "map_score.hpp"
#include "harness.hpp"
#include "runtime/channels.hpp"

using namespace pex::testing;
namespace ch = pex::runtime::channels;

namespace {

// The truth pose nearest in time to `utime` (SLAM_POSE carries its
// odometry's stamp, SIM_TRUTH the simulator's: both the simulated clock).
pex::pose_t truth_at(const std::vector<pex::pose_t>& truth, std::int64_t utime) {
  const pex::pose_t* best = &truth.front();
  for (const pex::pose_t& p : truth)
    if (std::llabs(p.utime - utime) < std::llabs(best->utime - utime)) best = &p;
  return *best;
}

// `to` seen from `from`: (forward, left, turn). The same for the truth and for
// SLAM whatever their frames, so their motions compare directly.
pex::geometry::Pose2 motion(const pex::pose_t& from, const pex::pose_t& to) {
  return pex::geometry::relative({from.x, from.y, from.theta}, {to.x, to.y, to.theta});
}

}  // namespace

TEST(SlamFaults, KilledSlamGoesOnFromItsCheckpointWithTheSameEpochAndNoJump) {
  const std::string checkpoint = make_temp_dir("faults-slam-state") + "/slam-filter.bin";
  ExplorationSet set("faults-slam",
                     {.slam = true,
                      .slam_keys = {{"checkpoint_file", "\"" + checkpoint + "\""}, {"checkpoint_period_s", "0.5"}}});
  std::vector<pex::pose_t> truth, slam_poses;
  std::vector<pex::slam_update_t> updates;
  std::vector<pex::polygon_map_t> maps;
  set.bus().on<pex::pose_t>(std::string(ch::kSimTruth), [&](const pex::pose_t& p) { truth.push_back(p); });
  set.bus().on<pex::pose_t>(std::string(ch::kSlamPose), [&](const pex::pose_t& p) { slam_poses.push_back(p); });
  set.bus().on<pex::slam_update_t>(std::string(ch::kSlamUpdate), [&](const pex::slam_update_t& u) { updates.push_back(u); });
  set.bus().on<pex::polygon_map_t>(std::string(ch::kMap), [&](const pex::polygon_map_t& m) { maps.push_back(m); });
  auto checkpoints_written = [&] {
    const auto it = set.bus().status().find("slam");
    return it == set.bus().status().end() ? std::int64_t{-1} : counter_of(it->second, "checkpoints_written");
  };
  // Mid-mission: a good part of the world mapped, SLAM some updates in, the
  // robot driving; then two more checkpoints, so the newest one is of now.
  ASSERT_TRUE(set.spin_sim(
      [&] {
        return !maps.empty() && maps.back().free_area_m2 > 30.0 && !updates.empty() && updates.back().generation >= 10 &&
               set.phase() == pex::explore_state_t::PHASE_MOVING;
      },
      300.0))
      << set.report_with_logs();
  const std::int64_t written = checkpoints_written();
  ASSERT_TRUE(set.spin_sim([&] { return checkpoints_written() >= written + 2; }, 10.0)) << set.report_with_logs();
  ASSERT_TRUE(set.spin_sim([&] { return set.phase() == pex::explore_state_t::PHASE_MOVING; }, 60.0))
      << set.report_with_logs();

  set.process("slam")->kill_hard();
  set.spin_sim([] { return false; }, 0.3);  // whatever the killed SLAM sent is in
  const pex::slam_update_t last_update = updates.back();
  const pex::pose_t last_pose = slam_poses.back();
  const std::size_t updates_before = updates.size(), poses_before = slam_poses.size();
  set.restart("slam");
  ASSERT_TRUE(set.spin_sim([&] { return slam_poses.size() > poses_before && updates.size() > updates_before; }, 30.0))
      << set.report_with_logs();

  // No jump: SLAM's motion from its last pose before the kill to its first
  // after the restart is the robot's, within a few cm (the restored filter
  // misses at most the updates of the last checkpoint period).
  const pex::pose_t first_pose = slam_poses[poses_before];
  const pex::geometry::Pose2 slam_moved = motion(last_pose, first_pose);
  const pex::geometry::Pose2 truth_moved = motion(truth_at(truth, last_pose.utime), truth_at(truth, first_pose.utime));
  const double error_m = std::hypot(slam_moved.x_m - truth_moved.x_m, slam_moved.y_m - truth_moved.y_m);
  EXPECT_LT(error_m, 0.05) << "SLAM moved (" << slam_moved.x_m << ", " << slam_moved.y_m << ") over the restart, the robot ("
                           << truth_moved.x_m << ", " << truth_moved.y_m << ")";
  EXPECT_LT(std::abs(slam_moved.theta_rad - truth_moved.theta_rad), 0.03)
      << "SLAM turned " << slam_moved.theta_rad << " rad over the restart, the robot " << truth_moved.theta_rad;
  // The same lineage: the same epoch, generations going on from the checkpoint's.
  // A copy: `updates` grows while the mission goes on below, and a reference
  // into it dangles once it reallocates (the `follows` check read freed
  // memory and failed at random).
  const pex::slam_update_t first_update = updates[updates_before];
  EXPECT_EQ(first_update.epoch, last_update.epoch) << "the restarted SLAM is a new filter";
  // At most the updates of one checkpoint period (0.5 s) are lost: a few
  // while the robot turns (an update per 0.25 rad).
  EXPECT_GE(first_update.generation, last_update.generation - 5) << "the restarted SLAM started from an old state";
  EXPECT_LE(first_update.generation, last_update.generation + 1);
  std::cout << "SLAM killed at generation " << last_update.generation << ", first update after the restart: generation "
            << first_update.generation << (first_update.republished ? " (republished)" : "") << "; motion over the restart "
            << "SLAM (" << slam_moved.x_m << ", " << slam_moved.y_m << ", " << slam_moved.theta_rad << "), truth (" << truth_moved.x_m
            << ", " << truth_moved.y_m << ", " << truth_moved.theta_rad << ")\n";

  expect_done_with_the_world_mapped(set);
  const auto other_epoch = std::count_if(updates.begin() + static_cast<std::ptrdiff_t>(updates_before), updates.end(),
                                         [&](const pex::slam_update_t& u) { return u.epoch != last_update.epoch; });
  EXPECT_EQ(other_epoch, 0) << "updates of another epoch after the restart";
  const auto& mapper = set.bus().status().at("polygon_mapper");
  EXPECT_EQ(counter_of(mapper, "slam_epoch_changes"), 0) << "the mapper dropped its maps for a new SLAM";
  // The explorer's trails (the way the robot drove, for tight plans and the
  // way home) go on in the same frame: kept, not started afresh; resynced on
  // the best trail once if the restarted SLAM counted generations again.
  const auto& explorer = set.bus().status().at("explorer");
  EXPECT_EQ(counter_of(explorer, "trail_epochs"), 0) << "the explorer started its trails afresh";
  const bool follows = first_update.generation == last_update.generation + (first_update.republished ? 0 : 1);
  EXPECT_EQ(counter_of(explorer, "trail_resyncs"), follows ? 0 : 1);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(std::filesystem::path(checkpoint).parent_path());
}

// SLAM updates after 0.5 m or 0.25 rad, and with the robot standing; a robot
// creeping to a goal goes seconds without an update. The mapper watched
// SLAM_UPDATE and went DEGRADED ("no SLAM_UPDATE for 3.1 s") a dozen times a
// mission; it watches SLAM_POSE (odometry rate), which stops only when SLAM
// does.
TEST(SlamFaults, ACreepingRobotKeepsTheMapperOkAndAKilledSlamMakesItDegraded) {
  ExplorationSet set("faults-creep", {.speed = 2.0, .slam = true, .held_back = {"explorer"}});
  std::vector<double> update_times;  // simulated s of each SLAM_UPDATE
  std::vector<std::pair<double, pex::daemon_status_t>> mapper;  // each status of the mapper, with simulated s
  set.bus().on<pex::slam_update_t>(std::string(ch::kSlamUpdate),
                                   [&](const pex::slam_update_t&) { update_times.push_back(set.sim_seconds()); });
  set.bus().on<pex::daemon_status_t>(std::string(ch::kDaemonStatus), [&](const pex::daemon_status_t& s) {
    if (s.name == "polygon_mapper") mapper.emplace_back(set.sim_seconds(), s);
  });
  auto mapper_ok = [&] { return !mapper.empty() && mapper.back().second.state == pex::daemon_status_t::STATE_OK; };
  ASSERT_TRUE(set.spin_sim([&] { return !update_times.empty() && mapper_ok(); }, 30.0)) << set.report_with_logs();

  // 10 simulated seconds at 4 cm/s: 0.4 m, no filter update, and no standing
  // republication either (more than 1 cm driven since the last update).
  const double creep_from = set.sim_seconds();
  const std::size_t statuses_before = mapper.size();
  ASSERT_TRUE(drive_until(set.bus(), 0.04, [&] { return set.sim_seconds() >= creep_from + 10.0; }, "slam_faults_test"))
      << set.report_with_logs();
  set.bus().publish(std::string(ch::kBaseCmd), velocity_command(0.0, 0.0, "slam_faults_test"));
  double longest_gap_s = 0.0, last = creep_from;
  for (const double t : update_times)
    if (t > creep_from) longest_gap_s = std::max(longest_gap_s, t - last), last = t;
  longest_gap_s = std::max(longest_gap_s, set.sim_seconds() - last);
  // The case itself: longer without an update than the mapper's input_timeout_s (3 s).
  ASSERT_GT(longest_gap_s, 4.0) << "SLAM updated every " << longest_gap_s << " s: the robot did not creep";
  ASSERT_GT(mapper.size(), statuses_before + 3) << "too few heartbeats of the mapper while creeping";
  for (std::size_t i = statuses_before; i < mapper.size(); ++i)
    EXPECT_EQ(+mapper[i].second.state, +pex::daemon_status_t::STATE_OK)
        << "at " << mapper[i].first << " s, the robot creeping, SLAM there:\n"
        << set.process("polygon_mapper")->output();

  set.process("slam")->kill_hard();
  auto slam_reported_away = [&] {
    return !mapper.empty() && mapper.back().second.state == pex::daemon_status_t::STATE_DEGRADED &&
           set.process("polygon_mapper")->output().find("no SLAM_POSE") != std::string::npos;
  };
  EXPECT_TRUE(set.spin_sim(slam_reported_away, 10.0)) << set.report_with_logs();
  // And OK again once SLAM is back (a new filter: the mapper starts its maps afresh).
  set.restart("slam");
  EXPECT_TRUE(set.spin_sim(mapper_ok, 20.0)) << set.report_with_logs();
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}
