#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "geometry/angle.hpp"
#include "geometry/point.hpp"
#include "geometry/pose2.hpp"
#include "geometry/rigid_fit.hpp"

namespace pex::geometry {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(WrapAngle, KeepsAnglesInsideTheRangeAsTheyAre) {
  for (double a : {0.0, -0.0, 0.5, -0.5, 3.0, -3.0, kPi, std::nextafter(-kPi, 0.0)}) {
    EXPECT_EQ(wrap_angle(a), a) << a;
  }
  EXPECT_TRUE(std::signbit(wrap_angle(-0.0)));
}

TEST(WrapAngle, GivesPiForMinusPiAndEveryOddMultiple) {
  EXPECT_EQ(wrap_angle(-kPi), kPi);
  EXPECT_EQ(wrap_angle(3.0 * kPi), kPi);
  EXPECT_EQ(wrap_angle(-3.0 * kPi), kPi);
  EXPECT_EQ(wrap_angle(2.0 * kPi), 0.0);
}

TEST(WrapAngle, NonFiniteGivesNan) {
  EXPECT_TRUE(std::isnan(wrap_angle(kNan)));
  EXPECT_TRUE(std::isnan(wrap_angle(kInf)));
  EXPECT_TRUE(std::isnan(wrap_angle(-kInf)));
}

// The result is the input less a whole number of 2pi, and within (-pi, pi].
// It also equals std::remainder(a, 2pi) (IEEE's exact remainder, which the
// mapper's and the planner's wraps used) wherever that is not -pi, so moving
// those callers to wrap_angle changed no figure but that one case.
TEST(WrapAngle, IsTheExactRemainderInMinusPiToPi) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> small(-4.0 * kPi, 4.0 * kPi);
  std::uniform_real_distribution<double> large(-1e6, 1e6);
  for (int i = 0; i < 200'000; ++i) {
    const double a = i % 2 ? small(rng) : large(rng);
    const double w = wrap_angle(a);
    ASSERT_GT(w, -kPi) << a;
    ASSERT_LE(w, kPi) << a;
    const double turns = (a - w) / (2.0 * kPi);
    ASSERT_NEAR(turns, std::round(turns), 1e-9) << a;
    ASSERT_EQ(w, std::remainder(a, 2.0 * kPi)) << a;
  }
}

TEST(WrapAnglePositive, MapsIntoZeroToTwoPi) {
  EXPECT_EQ(wrap_angle_positive(0.0), 0.0);
  EXPECT_EQ(wrap_angle_positive(-kPi), kPi);
  EXPECT_EQ(wrap_angle_positive(kPi), kPi);
  EXPECT_EQ(wrap_angle_positive(2.0 * kPi), 0.0);
  EXPECT_DOUBLE_EQ(wrap_angle_positive(-0.5), 2.0 * kPi - 0.5);
  EXPECT_DOUBLE_EQ(wrap_angle_positive(7.0), 7.0 - 2.0 * kPi);
  // The rounding edge the header states: just below 0 rounds up to 2pi.
  EXPECT_EQ(wrap_angle_positive(-1e-17), 2.0 * kPi);
  EXPECT_LT(wrap_angle_positive(-5e-16), 2.0 * kPi);
  EXPECT_TRUE(std::isnan(wrap_angle_positive(kNan)));
  EXPECT_TRUE(std::isnan(wrap_angle_positive(kInf)));
}

void expect_near(const Pose2& a, const Pose2& b, double tolerance = 1e-12) {
  EXPECT_NEAR(a.x_m, b.x_m, tolerance);
  EXPECT_NEAR(a.y_m, b.y_m, tolerance);
  EXPECT_NEAR(wrap_angle(a.theta_rad - b.theta_rad), 0.0, tolerance);
}

TEST(Pose2, ComposeMovesTheSecondIntoTheFirstsFrame) {
  // A robot at (1, 2) facing +y; a point 1 m ahead and 0.5 m to its left.
  const Pose2 robot{1.0, 2.0, kPi / 2};
  expect_near(compose(robot, {1.0, 0.5, 0.0}), {0.5, 3.0, kPi / 2});
  expect_near(compose(robot, {0.0, 0.0, kPi}), {1.0, 2.0, -kPi / 2});
}

TEST(Pose2, InverseAndRelativeUndoCompose) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> coordinate(-50.0, 50.0), angle(-kPi, kPi);
  for (int i = 0; i < 1000; ++i) {
    const Pose2 a{coordinate(rng), coordinate(rng), angle(rng)};
    const Pose2 b{coordinate(rng), coordinate(rng), angle(rng)};
    const Pose2 c{coordinate(rng), coordinate(rng), angle(rng)};
    expect_near(compose(a, inverse(a)), {}, 1e-12);
    expect_near(compose(inverse(a), a), {}, 1e-12);
    expect_near(relative(a, compose(a, b)), b, 1e-12);
    expect_near(relative(a, b), compose(inverse(a), b), 1e-12);
    expect_near(compose(compose(a, b), c), compose(a, compose(b, c)), 1e-12);
    const Pose2 ab = compose(a, b);
    EXPECT_GT(ab.theta_rad, -kPi);
    EXPECT_LE(ab.theta_rad, kPi);
  }
}

TEST(Pose2, IsFiniteChecksEveryField) {
  EXPECT_TRUE(is_finite(Pose2{1.0, 2.0, 3.0}));
  EXPECT_FALSE(is_finite(Pose2{kNan, 0.0, 0.0}));
  EXPECT_FALSE(is_finite(Pose2{0.0, kInf, 0.0}));
  EXPECT_FALSE(is_finite(Pose2{0.0, 0.0, kNan}));
}

// Transforming a point is compose's translation, bit for bit (same formula,
// same order), so code may use either without changing a figure.
TEST(PoseTransform, IsComposesTranslationExactly) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coordinate(-50.0, 50.0), angle(-kPi, kPi);
  for (int i = 0; i < 1000; ++i) {
    const Pose2 pose{coordinate(rng), coordinate(rng), angle(rng)};
    const Point p(coordinate(rng), coordinate(rng));
    const Pose2 composed = compose(pose, {p.x(), p.y(), 0.0});
    const Point moved = PoseTransform(pose)(p);
    EXPECT_EQ(moved.x(), composed.x_m);
    EXPECT_EQ(moved.y(), composed.y_m);
    EXPECT_EQ(transform(pose, p).x(), moved.x());
    EXPECT_EQ(transform(pose, p).y(), moved.y());
  }
}

TEST(BestRigidFit, RecoversAKnownMotionFromNoisyPoints) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-20.0, 20.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Pose2 motion{3.0, -1.5, 0.3};
  const PoseTransform apply(motion);
  std::vector<Point> from, to;
  for (int i = 0; i < 200; ++i) {
    const Point p(coordinate(rng), coordinate(rng));
    const Point q = apply(p);
    from.push_back(p);
    to.emplace_back(q.x() + noise(rng), q.y() + noise(rng));
  }
  const auto fit = best_rigid_fit(from, to);
  ASSERT_TRUE(fit);
  EXPECT_NEAR(fit->x_m, 3.0, 0.01);
  EXPECT_NEAR(fit->y_m, -1.5, 0.01);
  EXPECT_NEAR(fit->theta_rad, 0.3, 1e-3);
  // No better fit nearby: the residual grows either way.
  auto residual = [&](const Pose2& pose) {
    const PoseTransform t(pose);
    double sum = 0.0;
    for (std::size_t i = 0; i < from.size(); ++i) {
      const Point p = t(from[i]);
      sum += std::pow(p.x() - to[i].x(), 2) + std::pow(p.y() - to[i].y(), 2);
    }
    return sum;
  };
  const double best = residual(*fit);
  for (const Pose2 nudge : {Pose2{0.01, 0, 0}, Pose2{0, -0.01, 0}, Pose2{0, 0, 0.001}, Pose2{0, 0, -0.001}})
    EXPECT_GT(residual({fit->x_m + nudge.x_m, fit->y_m + nudge.y_m, fit->theta_rad + nudge.theta_rad}), best);
}

TEST(BestRigidFit, NeedsTwoCorrespondingPoints) {
  const std::vector<Point> one{Point(0, 0)}, two{Point(0, 0), Point(1, 0)};
  EXPECT_FALSE(best_rigid_fit(one, one));
  EXPECT_FALSE(best_rigid_fit(two, one));
  EXPECT_TRUE(best_rigid_fit(two, two));
}

}  // namespace
}  // namespace pex::geometry
