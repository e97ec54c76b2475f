#include "planning/visibility_graph.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "planning/exploration_planner.hpp"
#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

using E = mapping::EdgeType;
using testing::rectangle;
using testing::rectangle_hole;
using testing::typed_polygon;
using testing::disk;


// Every leg of the path stays in the C-space, and every point along it keeps
// `clearance` from the walls given.
void expect_path_in_cspace(const ConfigurationSpace& cs, const std::vector<Point>& path,
                           const std::vector<std::vector<Point>>& walls, double clearance) {
  ASSERT_GE(path.size(), 2u);
  for (std::size_t i = 1; i < path.size(); ++i) {
    EXPECT_TRUE(cs.segment_free(path[i - 1], path[i]));
    const double len = distance(path[i - 1], path[i]);
    for (double s = 0.0; s <= len; s += 0.005) {
      const Point p(path[i - 1].x() + (path[i].x() - path[i - 1].x()) * s / len,
                    path[i - 1].y() + (path[i].y() - path[i - 1].y()) * s / len);
      EXPECT_TRUE(cs.covers(p));
      for (const auto& wall : walls) ASSERT_GE(testing::distance_to_ring(p, wall), clearance) << p.x() << "," << p.y();
    }
  }
}

TEST(ShortestPaths, StraightLineInAnEmptyRoom) {
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10))}, disk(0.3)).ok);
  const auto sp = shortest_paths(cs, Point(1, 1), {Point(8, 5), Point(2, 9)});
  ASSERT_EQ(sp.length_m.size(), 2u);
  EXPECT_NEAR(sp.length_m[0], std::hypot(7.0, 4.0), 1e-12);
  EXPECT_NEAR(sp.length_m[1], std::hypot(1.0, 8.0), 1e-12);
  EXPECT_EQ(sp.path[0].size(), 2u);
}

TEST(ShortestPaths, AroundABlockIsOptimal) {
  // Block [4, 6] x [2, 8] in a 10 x 10 room; a point robot (radius 0) from
  // (2, 5) to (8, 5) goes over a top corner: 2 * |(2, 3)| + 2 by hand.
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10), {rectangle_hole(4, 2, 6, 8)})}, disk(0.0)).ok);
  const auto sp = shortest_paths(cs, Point(2, 5), {Point(8, 5)});
  const double expected = 2.0 * std::hypot(2.0, 3.0) + 2.0;
  // Nodes sit interior_offset_m off the corners: a few millimetres at most.
  EXPECT_NEAR(sp.length_m[0], expected, 5e-3);
  EXPECT_GE(sp.length_m[0], expected - 1e-9 - 4 * cs.options().interior_offset_m);
  ASSERT_EQ(sp.path[0].size(), 4u);
  expect_path_in_cspace(cs, sp.path[0], {{Point(4, 2), Point(6, 2), Point(6, 8), Point(4, 8)}}, 0.0);
}

TEST(ShortestPaths, DiskRobotKeepsItsClearance) {
  // The same block with a 0.4 m robot: the path bends around the round joins
  // and is longer than the point robot's, shorter than going around at the
  // corners of the grown box.
  const double r = 0.4;
  CSpaceOptions o = disk(r);
  o.points_per_circle = 32;
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10), {rectangle_hole(4, 2, 6, 8)})}, o).ok);
  const auto sp = shortest_paths(cs, Point(2, 5), {Point(8, 5)});
  ASSERT_TRUE(std::isfinite(sp.length_m[0]));
  const double point_robot = 2.0 * std::hypot(2.0, 3.0) + 2.0;
  const double grown_box_corners = 2.0 * std::hypot(2.0 - r, 3.0 + r) + 2.0 + 2 * r;
  EXPECT_GT(sp.length_m[0], point_robot);
  EXPECT_LT(sp.length_m[0], grown_box_corners);
  // The clearance of a chord of the round join (32 per circle) dips below r by
  // at most r * (1 - cos(pi / 32)).
  expect_path_in_cspace(cs, sp.path[0], {{Point(4, 2), Point(6, 2), Point(6, 8), Point(4, 8)}},
                        r * std::cos(M_PI / 32) - 1e-6);
}

TEST(ShortestPaths, TargetInAnotherPieceIsUnreachable) {
  // Two rooms joined by a 0.4 m gap: a 0.5 m robot cannot pass.
  mapping::TypedMultiPolygon map{typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(5, 0), Point(5, 2.3), Point(6, 2.3), Point(6, 0), Point(11, 0), Point(11, 5), Point(6, 5),
       Point(6, 2.7), Point(5, 2.7), Point(5, 5), Point(0, 5)},
      {}})};
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build(map, disk(0.25)).ok);
  EXPECT_EQ(cs.polygons().size(), 2u);
  const auto sp = shortest_paths(cs, Point(1, 1), {Point(4, 4), Point(9, 4)});
  EXPECT_TRUE(std::isfinite(sp.length_m[0]));
  EXPECT_FALSE(std::isfinite(sp.length_m[1]));
  EXPECT_TRUE(sp.path[1].empty());
}

TEST(ExplorationPlanner, ChoosesTheNearestFrontierAndRespectsTheBlacklist) {
  // A corridor 20 x 3 m with frontier at both ends; the robot near the left end.
  const auto map = mapping::TypedMultiPolygon{
      typed_polygon(rectangle(0, 0, 20, 3, {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier}))};
  PlannerOptions options;
  options.cspace.robot_radius_m = 0.3;
  options.turn_cost_m_per_rad = 0.0;
  const Pose2 robot{4.0, 1.5, 0.0};
  const Plan plan = plan_exploration(map, robot, {}, options);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_EQ(plan.candidates.size(), 2u);
  ASSERT_NE(plan.best_candidate(), nullptr);
  const auto& best = *plan.best_candidate();
  const double clearance = options.cspace.robot_radius_m + options.cspace.clearance_margin_m;
  EXPECT_NEAR(best.position.x(), clearance, 0.01);
  EXPECT_NEAR(best.position.y(), 1.5, 1e-6);
  EXPECT_NEAR(best.path_length_m, 4.0 - clearance, 0.01);
  EXPECT_EQ(best.path.front().x(), 4.0);
  EXPECT_EQ(plan.reachable_count(), 2);

  // With the left goal blacklisted the right one is chosen.
  const Plan other = plan_exploration(map, robot, {best.position}, options);
  ASSERT_TRUE(other.ok);
  ASSERT_NE(other.best_candidate(), nullptr);
  EXPECT_NEAR(other.best_candidate()->position.x(), 20.0 - clearance, 0.01);
  EXPECT_EQ(other.reachable_count(), 1);

  // Deterministic: the same input gives the same plan, bit for bit.
  const Plan again = plan_exploration(map, robot, {}, options);
  ASSERT_EQ(again.candidates.size(), plan.candidates.size());
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    EXPECT_EQ(again.candidates[i].position.x(), plan.candidates[i].position.x());
    EXPECT_EQ(again.candidates[i].path_length_m, plan.candidates[i].path_length_m);
  }
}

TEST(ExplorationPlanner, RobotPushedAgainstAWallStartsFromTheNearestCSpacePoint) {
  const auto map = mapping::TypedMultiPolygon{
      typed_polygon(rectangle(0, 0, 10, 3, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))};
  PlannerOptions options;
  options.cspace.robot_radius_m = 0.3;
  const Plan plan = plan_exploration(map, Pose2{5.0, 0.1, 0.0}, {}, options);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_NE(plan.best_candidate(), nullptr);
  const auto& path = plan.best_candidate()->path;
  ASSERT_GE(path.size(), 3u);
  EXPECT_EQ(path[0].y(), 0.1);  // the robot itself
  EXPECT_NEAR(path[1].y(), 0.35, 0.01);

  // Too far outside: a clear error, no crash.
  const Plan lost = plan_exploration(map, Pose2{5.0, -3.0, 0.0}, {}, options);
  EXPECT_FALSE(lost.ok);
  EXPECT_NE(lost.error.find("configuration space"), std::string::npos);
  const Plan nan = plan_exploration(map, Pose2{std::nan(""), 1.0, 0.0}, {}, options);
  EXPECT_FALSE(nan.ok);
}

}  // namespace
}  // namespace pex::planning
