#include "slam/odometry_drift.hpp"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace pex::slam {
namespace {

// A base whose heading bends by `drift` rad per metre and turns `scale` too
// far, driven in steps of 0.5 m with turns now and then; the matched turn is
// the true one plus the matcher's noise.
void drive(OdometryDrift& estimator, int steps, double drift, double scale, double noise_rad, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_rad);
  for (int i = 0; i < steps; ++i) {
    const double travel = i % 5 == 4 ? 0.05 : 0.5;  // every fifth step mostly a turn
    const double turn = i % 5 == 4 ? (i % 10 == 4 ? 0.25 : -0.25) : 0.01 * ((i % 3) - 1);
    const double matched = turn + drift * travel + scale * turn + noise(rng);
    estimator.observe(travel, turn, matched);
  }
}

TEST(OdometryDrift, LearnsTheDriftPerMetreAndTheTurnScale) {
  OdometryDriftOptions correcting;
  correcting.correct = true;
  OdometryDrift estimator(correcting);
  drive(estimator, 600, 0.008, 0.01, 0.002, 1);
  EXPECT_NEAR(estimator.drift_rad_per_m(), 0.008, 0.001);
  EXPECT_NEAR(estimator.turn_scale(), 0.01, 0.005);
  EXPECT_EQ(estimator.observations(), 600);
  // The correction takes it out of a step.
  const geometry::Pose2 corrected = estimator.correct({0.5, 0.0, 0.1});
  EXPECT_NEAR(corrected.theta_rad, 0.1 + 0.5 * estimator.drift_rad_per_m() + 0.1 * estimator.turn_scale(), 1e-12);
  EXPECT_EQ(corrected.x_m, 0.5);
}

TEST(OdometryDrift, ABaseWithoutDriftStaysAtZeroAndAFewStepsMoveItLittle) {
  OdometryDrift straight;
  drive(straight, 600, 0.0, 0.0, 0.002, 2);
  EXPECT_NEAR(straight.drift_rad_per_m(), 0.0, 0.0005);
  EXPECT_NEAR(straight.turn_scale(), 0.0, 0.005);
  // Three steps of a large drift: the ridge (20 m of no drift) holds it.
  OdometryDrift early;
  drive(early, 3, 0.04, 0.0, 0.0, 3);
  EXPECT_GT(early.drift_rad_per_m(), 0.0);
  EXPECT_LT(early.drift_rad_per_m(), 0.01);
}

// Backwards, the same wheels bend the heading the other way per metre: the
// drift goes with the signed forward travel.
TEST(OdometryDrift, DrivingBackwardsShowsTheSameDriftTheOtherWay) {
  OdometryDrift estimator;
  std::mt19937_64 rng(10);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (int i = 0; i < 600; ++i) {
    const double forward = i % 2 == 0 ? 0.5 : -0.5;
    estimator.observe(forward, 0.0, 0.008 * forward + noise(rng));
  }
  EXPECT_NEAR(estimator.drift_rad_per_m(), 0.008, 0.001);
  EXPECT_NEAR(estimator.correct({-0.5, 0.0, 0.0}).theta_rad, 0.0, 1e-12);  // not correcting
  OdometryDriftOptions correcting;
  correcting.correct = true;
  OdometryDrift applied(correcting);
  for (int i = 0; i < 600; ++i) applied.observe(i % 2 == 0 ? 0.5 : -0.5, 0.0, 0.008 * (i % 2 == 0 ? 0.5 : -0.5));
  EXPECT_LT(applied.correct({-0.5, 0.0, 0.0}).theta_rad, -0.003);
}

TEST(OdometryDrift, FollowsABaseThatChanges) {
  OdometryDrift estimator;
  drive(estimator, 600, 0.008, 0.0, 0.002, 4);
  drive(estimator, 2500, -0.004, 0.0, 0.002, 5);  // a wheel changed
  EXPECT_NEAR(estimator.drift_rad_per_m(), -0.004, 0.001);
}

TEST(OdometryDrift, OutliersAreNoEvidenceAndTheEstimateIsBounded) {
  OdometryDrift estimator;
  EXPECT_FALSE(estimator.observe(0.5, 0.0, 0.3));  // a slip or a wrong match
  EXPECT_FALSE(estimator.observe(0.5, std::nan(""), 0.0));
  EXPECT_EQ(estimator.refused(), 2);
  EXPECT_EQ(estimator.observations(), 0);
  EXPECT_EQ(estimator.drift_rad_per_m(), 0.0);
  OdometryDriftOptions options;
  options.max_drift_rad_per_m = 0.01;
  options.max_step_residual_rad = 0.2;
  OdometryDrift bounded(options);
  drive(bounded, 600, 0.08, 0.0, 0.0, 6);
  EXPECT_DOUBLE_EQ(bounded.drift_rad_per_m(), 0.01);
}

TEST(OdometryDrift, NotCorrectingChangesNoStepAndTheStateSurvivesAnArchive) {
  OdometryDrift estimator;
  drive(estimator, 300, 0.008, 0.01, 0.002, 7);
  archive::ByteWriter out;
  estimator.write(out);
  OdometryDrift restored;
  archive::ByteReader in(out.bytes());
  restored.read(in);
  EXPECT_EQ(restored.drift_rad_per_m(), estimator.drift_rad_per_m());
  EXPECT_EQ(restored.turn_scale(), estimator.turn_scale());
  EXPECT_EQ(restored.observations(), 300);
  // Both go on alike.
  drive(estimator, 10, 0.02, 0.0, 0.0, 8);
  drive(restored, 10, 0.02, 0.0, 0.0, 8);
  EXPECT_EQ(restored.drift_rad_per_m(), estimator.drift_rad_per_m());

  OdometryDrift shown_only;  // correct = false: estimated, not applied
  drive(shown_only, 300, 0.008, 0.0, 0.0, 9);
  EXPECT_GT(shown_only.drift_rad_per_m(), 0.005);
  const geometry::Pose2 step{0.5, 0.01, 0.1};
  EXPECT_EQ(shown_only.correct(step).theta_rad, 0.1);
}

}  // namespace
}  // namespace pex::slam
