#include <gtest/gtest.h>

#include <algorithm>

#include "evaluation/laps.hpp"

namespace pex::evaluation {
namespace {

CarmenLog three_scans() {
  CarmenLog log;
  for (int i = 0; i < 3; ++i) {
    CarmenLaser laser;
    laser.timestamp_s = 100.0 + i;
    laser.ranges_m = {static_cast<float>(i + 1)};
    laser.odometry = {static_cast<double>(i), 0.0, 0.0};
    log.order.push_back({true, log.lasers.size()});
    log.lasers.push_back(laser);
  }
  log.order.push_back({false, 0});
  log.odometry.push_back({100.5, {0.5, 0.0, 0.0}, 1.0, 0.0});
  return log;
}

TEST(Laps, OneLapIsTheLogItself) {
  const CarmenLog log = three_scans();
  const CarmenLog same = lap_log(log, 1, 1.0);
  EXPECT_EQ(same.lasers.size(), 3u);
  EXPECT_EQ(same.odometry.size(), 1u);
  EXPECT_EQ(same.order.size(), 4u);
}

TEST(Laps, PassesAlternateForwardsAndBackwardsWithContinuousTimeAndOdometry) {
  const CarmenLog laps = lap_log(three_scans(), 3, 2.0);
  ASSERT_EQ(laps.lasers.size(), 9u);
  EXPECT_TRUE(laps.odometry.empty());
  ASSERT_EQ(laps.order.size(), 9u);
  // Pass 0 as logged, pass 1 back along the path (the last scan first), pass 2 forwards.
  const double expected_t[] = {100, 101, 102, 104, 105, 106, 108, 109, 110};
  const double expected_x[] = {0, 1, 2, 2, 1, 0, 0, 1, 2};
  for (std::size_t i = 0; i < 9; ++i) {
    EXPECT_TRUE(laps.order[i].is_laser);
    EXPECT_EQ(laps.order[i].index, i);
    EXPECT_DOUBLE_EQ(laps.lasers[i].timestamp_s, expected_t[i]) << i;
    EXPECT_DOUBLE_EQ(laps.lasers[i].odometry.x_m, expected_x[i]) << i;
    // Each scan keeps the odometry pose it was taken at.
    EXPECT_EQ(laps.lasers[i].ranges_m[0], static_cast<float>(expected_x[i] + 1)) << i;
  }
  EXPECT_THROW(lap_log(three_scans(), 0, 1.0), std::invalid_argument);
}

TEST(Laps, RelationsHoldInEveryPassAtTheMappedTimes) {
  const CarmenLog log = three_scans();
  const LapTiming timing = lap_timing(log, 2.0);
  EXPECT_DOUBLE_EQ(timing.first_s, 100.0);
  EXPECT_DOUBLE_EQ(timing.last_s, 102.0);
  const std::vector<Relation> relations = {{100.0, 102.0, {2.0, 0.0, 0.0}}};
  const std::vector<Relation> laps = lap_relations(relations, timing, 3);
  ASSERT_EQ(laps.size(), 3u);
  EXPECT_DOUBLE_EQ(laps[0].t1_s, 100.0);
  EXPECT_DOUBLE_EQ(laps[0].t2_s, 102.0);
  EXPECT_DOUBLE_EQ(laps[1].t1_s, 106.0);  // backwards: the scan of 100 s comes at the pass's end
  EXPECT_DOUBLE_EQ(laps[1].t2_s, 104.0);
  EXPECT_DOUBLE_EQ(laps[2].t1_s, 108.0);
  EXPECT_DOUBLE_EQ(laps[2].t2_s, 110.0);
  EXPECT_DOUBLE_EQ(laps[1].pose_2_in_1.x_m, 2.0);

  // A trajectory driven as the lapped log says scores 0 on the lapped relations.
  const CarmenLog lapped = lap_log(log, 3, 2.0);
  std::vector<StampedPose> poses;
  for (const CarmenLaser& laser : lapped.lasers) poses.push_back({laser.timestamp_s, laser.odometry});
  std::sort(poses.begin(), poses.end(), [](const auto& a, const auto& b) { return a.timestamp_s < b.timestamp_s; });
  const MetricResult metric = evaluate_relations(poses, laps);
  EXPECT_EQ(metric.relations, 3u);
  EXPECT_NEAR(metric.trans_mean_m, 0.0, 1e-12);
}

}  // namespace
}  // namespace pex::evaluation
