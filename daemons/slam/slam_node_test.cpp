// The daemon's handlers without a bus: what they publish, and what they refuse.
#include "slam_node.hpp"

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

SlamNode make_node(Published& out, int particles = 5) {
  SlamNodeOptions options;
  options.filter.particle_count = particles;
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

}  // namespace
}  // namespace pex::slam_daemon
