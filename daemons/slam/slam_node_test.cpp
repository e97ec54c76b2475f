// The daemon's handlers without a bus: what they publish, and what they refuse.
#include "slam_node.hpp"
#include "slam_options.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace pex::slam_daemon {
namespace {

// A scan of a 4 m x 3 m box seen from its centre.
laser_scan_t box_scan(std::int64_t utime) {
  laser_scan_t scan{};
  scan.utime = utime;
  scan.angle_min = static_cast<float>(-std::numbers::pi / 2);
  scan.angle_increment = static_cast<float>(std::numbers::pi / 180);
  scan.range_min = 0.1f;
  scan.range_max = 30.0f;
  for (int i = 0; i < 180; ++i) {
    const double a = scan.angle_min + i * scan.angle_increment;
    const double tx = std::abs(std::cos(a)) > 1e-9 ? 2.0 / std::abs(std::cos(a)) : 1e9;
    const double ty = std::abs(std::sin(a)) > 1e-9 ? 1.5 / std::abs(std::sin(a)) : 1e9;
    scan.ranges.push_back(static_cast<float>(std::min(tx, ty)));
  }
  scan.nranges = static_cast<std::int32_t>(scan.ranges.size());
  return scan;
}

odometry_t odometry(std::int64_t utime, double x) {
  odometry_t msg{};
  msg.utime = utime;
  msg.x = x;
  return msg;
}

struct Published {
  std::vector<slam_update_t> updates;
  std::vector<pose_t> poses;
};

SlamNode make_node(Published& out, int particles = 5, bool record_trajectory = true) {
  SlamNodeOptions options;
  options.filter.particle_count = particles;
  options.record_trajectory = record_trajectory;
  SlamOutputs outputs;
  outputs.publish_update = [&out](const slam_update_t& m) { out.updates.push_back(m); };
  outputs.publish_pose = [&out](const pose_t& m) { out.poses.push_back(m); };
  return SlamNode(options, outputs);
}

TEST(SlamNode, FirstScanPublishesAnUpdateWithEveryParticle) {
  Published out;
  SlamNode node = make_node(out, 7);
  node.on_odometry(odometry(1000, 0.0));
  node.on_scan(box_scan(1000));
  ASSERT_EQ(out.updates.size(), 1u);
  const slam_update_t& update = out.updates[0];
  EXPECT_EQ(update.scan_utime, 1000);
  EXPECT_EQ(update.generation, 0);
  ASSERT_EQ(update.nparticles, 7);
  ASSERT_EQ(update.particles.size(), 7u);
  for (const particle_t& p : update.particles) EXPECT_EQ(p.parent, -1);
  // Weights are normalised: sum of exp(log_weight) is 1.
  double sum = 0.0;
  for (const particle_t& p : update.particles) sum += std::exp(p.log_weight);
  EXPECT_NEAR(sum, 1.0, 1e-9);
  // SLAM_POSE at odometry rate once initialised.
  node.on_odometry(odometry(2000, 0.05));
  ASSERT_FALSE(out.poses.empty());
  EXPECT_NEAR(out.poses.back().x, 0.05, 1e-9);
}

// A standing robot makes no filter updates; the particle set is still
// published once a second (scan time) with the newest scan, every particle its
// own parent, so a mapper started late gets its maps (no start-order deadlock).
TEST(SlamNode, StandingStillRepublishesTheParticleSetWithoutTouchingTheFilter) {
  Published out;
  SlamNode node = make_node(out, 4);
  for (std::int64_t t = 1'000'000; t <= 4'500'000; t += 20'000) {
    node.on_odometry(odometry(t, 0.0));
    if ((t / 20'000) % 2 == 0) node.on_scan(box_scan(t));
  }
  ASSERT_EQ(out.updates.size(), 4u);  // the first scan, then at 1, 2 and 3 s after it
  EXPECT_EQ(node.filter().generation(), 0);
  EXPECT_EQ(node.republished(), 3);
  for (std::size_t k = 1; k < out.updates.size(); ++k) {
    const slam_update_t& u = out.updates[k];
    EXPECT_EQ(u.generation, 0);
    EXPECT_FALSE(u.resampled);
    EXPECT_GE(u.scan_utime - out.updates[k - 1].scan_utime, 1'000'000);
    for (int i = 0; i < u.nparticles; ++i) EXPECT_EQ(u.particles[static_cast<std::size_t>(i)].parent, i);
  }
}

TEST(SlamNode, RefusesBadInputAndKeepsItsState) {
  Published out;
  SlamNode node = make_node(out);
  node.on_odometry(odometry(1000, 0.0));
  node.on_scan(box_scan(1000));
  laser_scan_t bad = box_scan(2000);
  bad.nranges = 5;  // disagrees with the array
  EXPECT_THROW(node.on_scan(bad), std::invalid_argument);
  laser_scan_t nan_geometry = box_scan(2000);
  nan_geometry.angle_increment = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(node.on_scan(nan_geometry), std::invalid_argument);
  // Found by the fuzz target slam_input: a laser 2.3e6 m off the robot made
  // the grid ask for 500 TB.
  laser_scan_t far_mount = box_scan(2000);
  far_mount.sensor_x = 2.3e6f;
  far_mount.sensor_y = 2.3e6f;
  EXPECT_THROW(node.on_scan(far_mount), std::invalid_argument);
  odometry_t nan_odometry = odometry(2000, 0.0);
  nan_odometry.theta = std::numeric_limits<double>::infinity();
  EXPECT_THROW(node.on_odometry(nan_odometry), std::invalid_argument);
  // NaN ranges are no returns, not an error.
  laser_scan_t nan_ranges = box_scan(3000);
  for (std::size_t i = 0; i < nan_ranges.ranges.size(); i += 2) nan_ranges.ranges[i] = std::nanf("");
  node.on_odometry(odometry(3000, 0.0));
  EXPECT_NO_THROW(node.on_scan(nan_ranges));
  EXPECT_EQ(out.updates.size(), 1u);
  EXPECT_EQ(node.scans_processed(), 2);
  EXPECT_EQ(node.filter().generation(), 0);
}

TEST(SlamNode, TrajectoryHasOneLinePerScan) {
  Published out;
  SlamNode node = make_node(out);
  for (int i = 0; i < 5; ++i) {
    node.on_odometry(odometry(1000 * (i + 1), 0.02 * i));
    node.on_scan(box_scan(1000 * (i + 1)));
  }
  node.flush();
  const std::string text = node.trajectory_text();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 5);
  EXPECT_EQ(text.rfind("0.001000 ", 0), 0u);
}

// Live (no --poses) the per-scan record is not kept: it would grow with the
// run's length.
TEST(SlamNode, WithoutRecordingNoScanIsKept) {
  Published out;
  SlamNode node = make_node(out, 5, false);
  for (int i = 0; i < 5; ++i) {
    node.on_odometry(odometry(1000 * (i + 1), 0.02 * i));
    node.on_scan(box_scan(1000 * (i + 1)));
  }
  node.flush();
  EXPECT_EQ(node.scans_processed(), 5);
  EXPECT_EQ(node.trajectory_text(), "");
}

// Odometry and a scan every 50 ms while driving along x at 0.4 m/s: a filter
// update every 0.5 m (25 steps).
void drive_steps(SlamNode& node, int from, int to) {
  for (int i = from; i < to; ++i) {
    const std::int64_t t = 1'000'000 + 50'000 * static_cast<std::int64_t>(i);
    node.on_odometry(odometry(t, 0.02 * i));
    node.on_scan(box_scan(t));
  }
}

void expect_same_update(const slam_update_t& a, const slam_update_t& b) {
  EXPECT_EQ(a.epoch, b.epoch);
  EXPECT_EQ(a.generation, b.generation);
  EXPECT_EQ(a.scan_utime, b.scan_utime);
  EXPECT_EQ(a.republished, b.republished);
  EXPECT_EQ(a.resampled, b.resampled);
  EXPECT_EQ(a.best, b.best);
  ASSERT_EQ(a.particles.size(), b.particles.size());
  for (std::size_t i = 0; i < a.particles.size(); ++i) {
    EXPECT_EQ(a.particles[i].x, b.particles[i].x);
    EXPECT_EQ(a.particles[i].y, b.particles[i].y);
    EXPECT_EQ(a.particles[i].theta, b.particles[i].theta);
    EXPECT_EQ(a.particles[i].log_weight, b.particles[i].log_weight);
    EXPECT_EQ(a.particles[i].parent, b.particles[i].parent);
  }
}

// kill -9 and restart from the checkpoint: the restored node publishes what
// the node that never stopped publishes, update for update and pose for pose:
// the same epoch, the next generation (so the mapper follows its parents), no
// jump in SLAM_POSE.
// A robot driving makes updates every 0.5 m: 1.25 s apart at 0.4 m/s, longer
// than the republish period. Its scans between updates must not go out at
// unmatched poses (odometry plus motion noise drew slanted walls into the
// polygon maps); once it stands, the set is republished again.
TEST(SlamNode, ADrivingRobotIsNotRepublishedOnlyAStandingOne) {
  Published out;
  SlamNode node = make_node(out, 4);
  drive_steps(node, 0, 101);  // 5 s, 2 m
  EXPECT_EQ(node.republished(), 0);
  const std::size_t driving_updates = out.updates.size();
  EXPECT_EQ(driving_updates, 5u);  // the first scan and one every 0.5 m
  for (int i = 101; i < 200; ++i) {  // stands at x = 2.0 m for 5 s
    const std::int64_t t = 1'000'000 + 50'000 * static_cast<std::int64_t>(i);
    node.on_odometry(odometry(t, 2.0));
    node.on_scan(box_scan(t));
  }
  EXPECT_GE(node.republished(), 3);
  for (std::size_t k = driving_updates; k < out.updates.size(); ++k) EXPECT_TRUE(out.updates[k].republished);
}

TEST(SlamNode, ARestoredNodeGoesOnWithTheSameEpochAndTheNextGeneration) {
  Published never_stopped_out, restarted_out;
  SlamNode never_stopped = make_node(never_stopped_out);
  drive_steps(never_stopped, 0, 60);
  const std::string saved = never_stopped.checkpoint();
  const std::size_t updates_at_save = never_stopped_out.updates.size();
  const std::size_t poses_at_save = never_stopped_out.poses.size();
  const std::int64_t generation_at_save = never_stopped.filter().generation();
  ASSERT_GE(generation_at_save, 2);
  drive_steps(never_stopped, 60, 130);

  SlamNode restarted = make_node(restarted_out);
  ASSERT_EQ(restarted.restore(saved), "");
  EXPECT_EQ(restarted.epoch(), never_stopped.epoch());
  drive_steps(restarted, 60, 130);
  ASSERT_GE(restarted_out.updates.size(), 2u);
  ASSERT_EQ(restarted_out.updates.size(), never_stopped_out.updates.size() - updates_at_save);
  // The first update after the restore continues the saved generation (a
  // republish of it while no update is due, as the node that never stopped).
  const auto first_update = std::find_if(restarted_out.updates.begin(), restarted_out.updates.end(),
                                         [](const slam_update_t& u) { return !u.republished; });
  ASSERT_NE(first_update, restarted_out.updates.end());
  EXPECT_EQ(first_update->generation, generation_at_save + 1);
  for (std::size_t k = 0; k < restarted_out.updates.size(); ++k)
    expect_same_update(restarted_out.updates[k], never_stopped_out.updates[updates_at_save + k]);
  ASSERT_EQ(restarted_out.poses.size(), never_stopped_out.poses.size() - poses_at_save);
  for (std::size_t k = 0; k < restarted_out.poses.size(); ++k) {
    EXPECT_EQ(restarted_out.poses[k].x, never_stopped_out.poses[poses_at_save + k].x) << k;
    EXPECT_EQ(restarted_out.poses[k].theta, never_stopped_out.poses[poses_at_save + k].theta) << k;
  }
  EXPECT_EQ(restarted.scans_processed(), never_stopped.scans_processed());
  EXPECT_TRUE(restarted.checkpoint() == never_stopped.checkpoint());
}

TEST(SlamNode, ABrokenCheckpointIsRefusedWithAReasonAndChangesNothing) {
  Published out;
  SlamNode source = make_node(out);
  drive_steps(source, 0, 40);
  const std::string good = source.checkpoint();
  SlamNode node = make_node(out);
  drive_steps(node, 0, 10);
  const std::string before = node.checkpoint();
  std::string flipped = good;
  flipped[good.size() / 2] = static_cast<char>(flipped[good.size() / 2] ^ 1);
  std::string other_version = good;
  other_version[8] = 2;  // the format version's low byte
  for (const std::string& bad : {good.substr(0, good.size() - 1), flipped, other_version, std::string("PEXSLAMN")}) {
    EXPECT_NE(node.restore(bad), "");
    EXPECT_TRUE(node.checkpoint() == before);
  }
  // Another particle count: the filter inside refuses, and nothing changes.
  Published other_out;
  SlamNode other = make_node(other_out, 6);
  const std::string why = node.restore(other.checkpoint());
  EXPECT_NE(why.find("6 particles"), std::string::npos) << why;
  EXPECT_TRUE(node.checkpoint() == before);
  EXPECT_EQ(node.restore(good), "");
  EXPECT_EQ(node.epoch(), source.epoch());
}

// Issue 12: null_log_likelihood = -1e308 made 1244 of 1318 poses NaN, exit 0.
TEST(SlamOptions, NullLogLikelihoodOutsideItsRangeIsAConfigError) {
  for (const char* value : {"-1e308", "1e308", "0.5", "-101", "nan"}) {
    auto config = runtime::ConfigReader::from_string(std::string("[grid]\nnull_log_likelihood = ") + value + "\n", "slam.toml");
    EXPECT_THROW(load_options(config), runtime::ConfigError) << value;
  }
  for (const char* value : {"-0.5", "0", "-100"}) {
    auto config = runtime::ConfigReader::from_string(std::string("[grid]\nnull_log_likelihood = ") + value + "\n", "slam.toml");
    EXPECT_EQ(load_options(config).filter.grid.null_log_likelihood, std::stod(value)) << value;
  }
}

// [odometry_drift]: each key reaches the filter's options, out-of-range
// values are config errors, and the shipped file only shows the estimate.
TEST(SlamOptions, OdometryDriftKeysReachTheFilterAndAreChecked) {
  auto config = runtime::ConfigReader::from_string(
      "[odometry_drift]\ncorrect = true\nforgetting = 0.99\nprior_travel_m = 2.0\nprior_turn_rad = 1.0\n"
      "max_drift_rad_per_m = 0.02\nmax_turn_scale = 0.05\nmax_step_residual_rad = 0.1\n",
      "slam.toml");
  const auto drift = load_options(config).filter.odometry_drift;
  EXPECT_TRUE(drift.correct);
  EXPECT_EQ(drift.forgetting, 0.99);
  EXPECT_EQ(drift.prior_travel_m, 2.0);
  EXPECT_EQ(drift.prior_turn_rad, 1.0);
  EXPECT_EQ(drift.max_drift_rad_per_m, 0.02);
  EXPECT_EQ(drift.max_turn_scale, 0.05);
  EXPECT_EQ(drift.max_step_residual_rad, 0.1);
  for (const char* bad : {"forgetting = 0.2", "forgetting = 1.5", "prior_travel_m = 0", "max_turn_scale = 2",
                          "max_drift_rad_per_m = -0.1"}) {
    auto wrong = runtime::ConfigReader::from_string(std::string("[odometry_drift]\n") + bad + "\n", "slam.toml");
    EXPECT_THROW(load_options(wrong), runtime::ConfigError) << bad;
  }
  // The key before it was named `correct` is no key (finish(): unknown keys).
  auto renamed = runtime::ConfigReader::from_string("[odometry_drift]\nenabled = true\n", "slam.toml");
  (void)load_options(renamed);
  EXPECT_THROW(renamed.finish(), runtime::ConfigError);
  auto shipped = runtime::ConfigReader::from_file(std::string(PEX_SOURCE_DIR) + "/config/slam.toml");
  EXPECT_FALSE(load_options(shipped).filter.odometry_drift.correct);
}

}  // namespace
}  // namespace pex::slam_daemon
