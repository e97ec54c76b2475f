#include "kinematics/kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace pex::kinematics {
namespace {

DriveGeometry geometry() {
  DriveGeometry g;
  g.wheel_radius_m = 0.1;
  g.wheel_base_m = 0.5;
  g.counts_per_rev = 1000.0;
  g.gear_ratio = 10.0;
  return g;
}

TEST(DriveGeometry, CountsPerMetreAndValidation) {
  // one wheel turn = 10000 counts = 2 pi 0.1 m
  EXPECT_NEAR(geometry().counts_per_m(), 10000.0 / (0.2 * std::numbers::pi), 1e-9);
  EXPECT_EQ(geometry().validate(), "");
  DriveGeometry bad = geometry();
  bad.wheel_base_m = 0.0;
  EXPECT_NE(bad.validate(), "");
  bad = geometry();
  bad.gear_ratio = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(bad.validate(), "");
}

TEST(Kinematics, WheelsAndBodyAreInverse) {
  WheelSpeeds w = to_wheels(geometry(), {0.5, 1.0});
  EXPECT_DOUBLE_EQ(w.left_mps, 0.25);
  EXPECT_DOUBLE_EQ(w.right_mps, 0.75);
  BodyVelocity b = to_body(geometry(), w);
  EXPECT_DOUBLE_EQ(b.v_mps, 0.5);
  EXPECT_DOUBLE_EQ(b.omega_radps, 1.0);
}

TEST(VelocityLimiter, ClampsSpeedKeepsCurvatureAndLimitsAcceleration) {
  VelocityLimiter::Options o;
  o.max_speed_mps = 1.0;
  o.max_omega_radps = 10.0;
  o.max_wheel_speed_mps = 1.0;
  o.max_wheel_accel_mps2 = 2.0;
  VelocityLimiter limiter(geometry(), o);
  // 0.1 s at 2 m/s^2: at most 0.2 m/s change per wheel
  WheelSpeeds w = limiter.step({5.0, 0.0}, 0.1);
  EXPECT_DOUBLE_EQ(w.left_mps, 0.2);
  EXPECT_DOUBLE_EQ(w.right_mps, 0.2);
  for (int i = 0; i < 20; ++i) w = limiter.step({5.0, 0.0}, 0.1);
  EXPECT_DOUBLE_EQ(w.left_mps, 1.0);  // clamped to max_speed
  // A turn that would need 1.5 m/s on the outer wheel is scaled down, curvature kept.
  limiter.reset();
  for (int i = 0; i < 50; ++i) w = limiter.step({1.0, 2.0}, 0.1);  // wheels 0.5 / 1.5
  EXPECT_DOUBLE_EQ(w.right_mps, 1.0);
  EXPECT_NEAR(w.left_mps / w.right_mps, 0.5 / 1.5, 1e-12);
  // NaN is a stop, reached within the acceleration limit.
  w = limiter.step({std::numeric_limits<double>::quiet_NaN(), 0.0}, 0.1);
  EXPECT_NEAR(w.right_mps, 0.8, 1e-12);
  EXPECT_NEAR(w.left_mps, 1.0 / 3.0 - 0.2 / 3.0, 1e-12);
}

TEST(Odometry, StraightLineAndCircle) {
  const DriveGeometry g = geometry();
  OdometryIntegrator odo(g, {});
  const double per_m = g.counts_per_m();
  odo.update(0, 0, 0);
  // 1 m straight in 100 steps of 10 ms
  for (int i = 1; i <= 100; ++i) {
    const auto c = static_cast<std::int32_t>(std::lround(per_m * i / 100.0));
    odo.update(c, c, i * 10'000);
  }
  EXPECT_NEAR(odo.state().pose.x_m, 1.0, 1e-4);
  EXPECT_NEAR(odo.state().pose.y_m, 0.0, 1e-9);
  EXPECT_NEAR(odo.state().v_mps, 1.0, 0.01);
  // A full circle of radius 0.5 m turning left: right wheel 0.75, left 0.25 of the centre path
  OdometryIntegrator circle(g, {});
  circle.update(0, 0, 0);
  const double path = 2.0 * std::numbers::pi * 0.5;
  const int n = 2000;
  for (int i = 1; i <= n; ++i) {
    const double s = path * i / n;
    circle.update(static_cast<std::int32_t>(std::lround(per_m * s * 0.5)),
                  static_cast<std::int32_t>(std::lround(per_m * s * 1.5)), i * 1000);
  }
  EXPECT_NEAR(circle.state().pose.x_m, 0.0, 2e-3);
  EXPECT_NEAR(circle.state().pose.y_m, 0.0, 2e-3);
  EXPECT_NEAR(circle.state().pose.theta_rad, 0.0, 2e-3);
}

TEST(Odometry, CovarianceGrowsWithDistanceAndCountersWrap) {
  const DriveGeometry g = geometry();
  OdometryIntegrator odo(g, {});
  const std::int32_t start = std::numeric_limits<std::int32_t>::max() - 1000;
  odo.update(start, start, 0);
  double last_var = 0.0;
  for (int i = 1; i <= 50; ++i) {
    // crosses the int32 wrap after 1000 counts
    const std::int32_t c = static_cast<std::int32_t>(static_cast<std::uint32_t>(start) + 100u * i);
    ASSERT_TRUE(odo.update(c, c, i * 10'000));
    EXPECT_GT(odo.state().covariance[0], last_var);
    last_var = odo.state().covariance[0];
  }
  EXPECT_NEAR(odo.state().pose.x_m, 5000.0 / g.counts_per_m(), 1e-9);
  // sigma^2 = 0.05^2 per metre travelled
  EXPECT_NEAR(odo.state().covariance[0], 0.0025 * odo.state().distance_m, 1e-9);
  EXPECT_EQ(odo.rejected_jumps(), 0u);
}

TEST(Odometry, ImplausibleJumpRebaselines) {
  OdometryIntegrator odo(geometry(), {});
  odo.update(100, 100, 0);
  odo.update(200, 200, 10'000);
  const double x = odo.state().pose.x_m;
  odo.update(0, 0, 20'000);  // a drive restarted: counter back to 0 -- a small jump, accepted as motion
  odo.update(5'000'000, 5'000'000, 30'000);  // 5e6 counts = 314 m in 10 ms: rejected
  EXPECT_EQ(odo.rejected_jumps(), 1u);
  EXPECT_LT(odo.state().pose.x_m, x + 1.0);
  odo.update(5'000'100, 5'000'100, 40'000);  // continues from the new baseline
  EXPECT_GT(odo.state().pose.x_m, x - 1.0);
}

}  // namespace
}  // namespace pex::kinematics

namespace pex::kinematics {
namespace {

TEST(Odometry, VelocityIsAveragedOverTheWindowDespiteTimingJitter) {
  const DriveGeometry g = geometry();
  OdometryIntegrator odo(g, {});
  const double per_m = g.counts_per_m();
  // Counts sampled every 10 ms exactly at 0.25 m/s, but received with up to
  // +-3 ms jitter: the reception times carry the jitter.
  const int jitter_us[] = {0, 3000, -2000, 2500, -3000, 1000, -1500, 2000};
  odo.update(0, 0, 0);
  double worst = 0.0;
  for (int i = 1; i <= 100; ++i) {
    const auto c = static_cast<std::int32_t>(std::lround(per_m * 0.25 * i * 0.01));
    odo.update(c, c, i * 10'000 + jitter_us[i % 8]);
    if (i > 10) worst = std::max(worst, std::abs(odo.state().v_mps - 0.25));
  }
  // One-update differences would be off by up to 6/10 = 60 %; the window keeps it near.
  EXPECT_LT(worst, 0.25 * 0.15);
  EXPECT_GT(worst, 0.0);
}

}  // namespace
}  // namespace pex::kinematics
