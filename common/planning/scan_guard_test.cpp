#include "planning/scan_guard.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace pex::planning {
namespace {

using mapping::Point;

TEST(ScanGuard, AWallAheadLimitsTheSpeedToWhatCanStopBeforeIt) {
  std::vector<Point> wall;
  for (double y = -2.0; y <= 2.0; y += 0.01) wall.emplace_back(1.0, y);  // 1 m ahead
  const double free = free_distance_ahead(wall, 0.25);
  EXPECT_NEAR(free, 0.75, 1e-3);
  ScanGuardOptions o;
  const double v = max_safe_speed(free, o);
  EXPECT_NEAR(v, std::sqrt(2.0 * 0.5 * (0.75 - 0.03)), 1e-3);
  // Braking from v at the guard's deceleration ends margin_m short of the wall.
  EXPECT_NEAR(v * v / (2.0 * o.max_decel_mps2), free - o.margin_m, 1e-3);
}

TEST(ScanGuard, ReturnsBesideOrBehindTheBodyDoNotStopIt) {
  std::vector<Point> points;
  for (double x = -3.0; x <= 3.0; x += 0.01) {
    points.emplace_back(x, 0.26);   // a corridor wall 1 cm beside a 0.25 m body
    points.emplace_back(x, -0.30);
  }
  points.emplace_back(-0.5, 0.0);   // behind
  EXPECT_TRUE(std::isinf(free_distance_ahead(points, 0.25)));
  EXPECT_TRUE(std::isinf(max_safe_speed(free_distance_ahead(points, 0.25), {})));
}

TEST(ScanGuard, ACornerAtTheBodysEdgeCountsWhereTheDiskMeetsIt) {
  // A point 0.2 m to the side: the disk's rim meets it 0.15 m behind the front.
  const std::vector<Point> corner{Point(1.0, 0.2)};
  EXPECT_NEAR(free_distance_ahead(corner, 0.25), 1.0 - 0.15, 1e-9);
  // Touching already: no forward speed at all.
  const std::vector<Point> touching{Point(0.2, 0.0)};
  EXPECT_EQ(free_distance_ahead(touching, 0.25), 0.0);
  EXPECT_EQ(max_safe_speed(0.0, {}), 0.0);
  EXPECT_EQ(max_safe_speed(0.02, {}), 0.0);  // within the margin
}

}  // namespace
}  // namespace pex::planning
