#include "planning/keep_out.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "geometry/point.hpp"
#include "mapping/test_support.hpp"
#include "planning/exploration_planner.hpp"
#include "planning/live_view.hpp"
#include "planning/mission.hpp"
#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

using mapping::EdgeType;
using mapping::Point;
using E = EdgeType;

KeepOut parse_ok(const std::string& text, const Pose2& start = {}, double width = 0.1) {
  auto parsed = parse_keep_out(text, "keep.wkt", start, width);
  if (auto* e = std::get_if<KeepOutError>(&parsed)) ADD_FAILURE() << e->message;
  return std::get<KeepOut>(parsed);
}

std::string parse_error(const std::string& text) {
  auto parsed = parse_keep_out(text, "keep.wkt", Pose2{}, 0.1);
  if (auto* e = std::get_if<KeepOutError>(&parsed)) return e->message;
  return "";
}

bool covers(const mapping::TypedMultiPolygon& polygons, const Point& p) {
  for (const auto& polygon : polygons)
    if (boost::geometry::covered_by(p, polygon.geometry)) return true;
  return false;
}

TEST(KeepOut, LinesAreStripsAndAreasAreAreasInTheMapFrame) {
  // The file's frame has the robot starting at (10, 20) facing +y: the map's
  // x axis is the file's +y, the map's y axis the file's -x.
  const Pose2 start{10.0, 20.0, std::numbers::pi / 2};
  const KeepOut k = parse_ok(
      "# glass along the corridor\n"
      "\n"
      "LINESTRING (10 24, 8 24, 8 25)\n"
      "POLYGON ((12 30, 14 30, 14 32, 12 32, 12 30))\n",
      start, 0.1);
  EXPECT_EQ(k.lines, 2);
  EXPECT_EQ(k.areas, 1);
  // (10, 24) in the file is 4 m ahead of the start: map (4, 0); (8, 24) is map (4, 2).
  EXPECT_TRUE(covers(k.obstacles, Point(4.0, 1.0)));
  EXPECT_TRUE(covers(k.obstacles, Point(4.04, 1.0)));   // within half the width
  EXPECT_FALSE(covers(k.obstacles, Point(4.07, 1.0)));  // beyond it
  EXPECT_TRUE(covers(k.obstacles, Point(4.0, 0.01)));
  EXPECT_FALSE(covers(k.obstacles, Point(4.0, -0.02)));  // flat at its end: a line drawn to a jamb narrows no door
  EXPECT_TRUE(covers(k.obstacles, Point(4.5, 2.0)));     // the second segment: file (8, 24.5) = map (4.5, 2)
  EXPECT_TRUE(covers(k.obstacles, Point(3.97, 2.03)));   // round at the corner (4, 2)
  // The area: file x 12..14, y 30..32 is map x 10..12, y -4..-2.
  EXPECT_TRUE(covers(k.obstacles, Point(11.0, -3.0)));
  EXPECT_FALSE(covers(k.obstacles, Point(11.0, -1.5)));
  for (const auto& polygon : k.obstacles)
    for (const auto& ring : polygon.edge_types)
      for (E t : ring) EXPECT_EQ(t, E::kObstacle);
  std::string why;
  EXPECT_TRUE(mapping::is_valid(k.obstacles, &why)) << why;
}

TEST(KeepOut, ErrorsNameTheLine) {
  EXPECT_EQ(parse_error("# nothing\n\n"), "");
  EXPECT_NE(parse_error("LINESTRING (0 0, 1 1)\nPOINT (1 2)\n").find("keep.wkt:2: unsupported"), std::string::npos);
  EXPECT_NE(parse_error("\nLINESTRING (0 0, x 1)\n").find("keep.wkt:2: bad WKT"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING (0 0, inf 1)\n").find("keep.wkt:1: coordinate"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING (0 0, 1e9 1)\n").find("beyond 1e5"), std::string::npos);
  EXPECT_NE(parse_error("POLYGON ((0 0, 1 0, 1 1))\n").find("keep.wkt:1: POLYGON ring not closed"), std::string::npos);
  EXPECT_NE(parse_error("POLYGON ((0 0, 2 2, 2 0, 0 2, 0 0))\n").find("not a valid area"), std::string::npos);
}

// Two rooms, 4 x 4 m, the wall between them at x = 4 .. 4.2 glass but for a
// door at y = 1.5 .. 2.5: the laser saw room B through the glass, so the map
// is one free room 8.2 m long; room B's far side is a frontier.
mapping::TypedMultiPolygon map_seen_through_glass() {
  return {testing::typed_polygon(testing::rectangle(0, 0, 8.2, 4, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))};
}

PlannerOptions options() {
  PlannerOptions o;
  o.cspace.robot_radius_m = 0.27;
  o.cspace.clearance_margin_m = 0.05;
  o.approach_range_m = 0.0;
  return o;
}

// Where the path first crosses x = 4.1 (NaN: it does not).
double crossing_y(const std::vector<Point>& path) {
  for (std::size_t k = 1; k < path.size(); ++k) {
    const auto& a = path[k - 1];
    const auto& b = path[k];
    if ((a.x() - 4.1) * (b.x() - 4.1) <= 0.0 && a.x() != b.x())
      return a.y() + (b.y() - a.y()) * (4.1 - a.x()) / (b.x() - a.x());
  }
  return std::nan("");
}

TEST(KeepOut, APlanGoesThroughTheDoorNotTheGlassAlsoWithTheLiveView) {
  const Pose2 robot{2.0, 0.7, 0.0};
  // The glass in a file whose frame is the world's, the robot starting at (1, 1).
  const Pose2 start{1.0, 1.0, 0.0};
  char text[256];
  std::snprintf(text, sizeof text, "LINESTRING (%g %g, %g %g)\nLINESTRING (%g %g, %g %g)\n", 4.1 + 1, 0.0 + 1,
                4.1 + 1, 1.5 + 1, 4.1 + 1, 2.5 + 1, 4.1 + 1, 4.0 + 1);
  const KeepOut k = parse_ok(text, start, 0.05);
  ASSERT_EQ(k.lines, 2);
  // The robot's pose is in the map frame, as the map.
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map_seen_through_glass());
  request.pose = robot;
  request.options = options();
  // The laser sees through the glass: its live view spans both rooms.
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 8.2, 4);
  const mapping::testing::ScanSpec spec;
  LiveViewOptions view;
  view.range_m = 6.0;
  request.live_view = std::make_shared<const mapping::TypedMultiPolygon>(
      live_view(mapping::testing::cast_scan(walls, robot, spec), spec.angle_min, spec.angle_increment, 0.05, robot, view));
  ASSERT_FALSE(request.live_view->empty());

  const PlanResult without = compute_plan(request);
  ASSERT_TRUE(without.plan.ok) << without.plan.error;
  ASSERT_NE(without.plan.best_candidate(), nullptr);
  const double y_without = crossing_y(without.plan.best_candidate()->path);
  EXPECT_LT(y_without, 1.5) << "without the keep-out the path crosses the glass";

  request.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(k.obstacles);
  const PlanResult with = compute_plan(request);
  ASSERT_TRUE(with.plan.ok) << with.plan.error;
  const GoalCandidate* goal = with.plan.best_candidate();
  ASSERT_NE(goal, nullptr) << "room B is reached through the door";
  EXPECT_GT(goal->position.x(), 4.2);
  const double y = crossing_y(goal->path);
  EXPECT_GT(y, 1.5 + 0.27);
  EXPECT_LT(y, 2.5 - 0.27);

  // The door closed too: room B has no path.
  const KeepOut wall = parse_ok("LINESTRING (5.1 1, 5.1 5)\n", start, 0.05);
  request.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(wall.obstacles);
  const PlanResult shut = compute_plan(request);
  ASSERT_TRUE(shut.plan.ok) << shut.plan.error;
  const GoalCandidate* none = shut.plan.best_candidate();
  EXPECT_TRUE(none == nullptr || none->position.x() < 4.1) << "no goal behind the keep-out line";
}

TEST(KeepOut, NoneOrDisjointLeavesTheMapAsItIs) {
  const auto map = map_seen_through_glass();
  bool failed = true;
  EXPECT_EQ(mapping::vertex_count(without_keep_out(map, {}, &failed)), mapping::vertex_count(map));
  EXPECT_FALSE(failed);
  const KeepOut far = parse_ok("POLYGON ((20 20, 21 20, 21 21, 20 21, 20 20))\n");
  EXPECT_NEAR(mapping::area(without_keep_out(map, far.obstacles, &failed)), mapping::area(map), 1e-5);  // the overlay's grid
  EXPECT_FALSE(failed);
  const KeepOut half = parse_ok("POLYGON ((4 -1, 9 -1, 9 5, 4 5, 4 -1))\n");
  EXPECT_NEAR(mapping::area(without_keep_out(map, half.obstacles, &failed)), 16.0, 1e-6);
  EXPECT_FALSE(failed);
}

}  // namespace
}  // namespace pex::planning
