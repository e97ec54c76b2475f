#include "planning/keep_out.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <utility>
#include <vector>

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
  // Within the file's bound but beyond the map's extent once in the map frame (a start pose far off).
  EXPECT_NE(parse_error("LINESTRING (0 0, 9000 1)\n").find("keep.wkt:1: beyond 8191 m"), std::string::npos)
      << parse_error("LINESTRING (0 0, 9000 1)\n");
  EXPECT_NE(parse_error("\nPOLYGON ((0 0, 1 0, 1 -9000, 0 0))\n").find("keep.wkt:2: beyond"), std::string::npos);
  EXPECT_NE(parse_error("POLYGON ((0 0, 1 0, 1 1))\n").find("keep.wkt:1: POLYGON ring not closed"), std::string::npos);
  EXPECT_NE(parse_error("POLYGON ((0 0, 2 2, 2 0, 0 2, 0 0))\n").find("not a valid area"), std::string::npos);
}

// Two rooms, 4 x 4 m, the wall between them at x = 4 .. 4.2 glass but for a
// door at y = 1.5 .. 2.5: the laser saw room B through the glass, so the map
// is one free room 8.2 m long; room B's far side is a frontier.
mapping::TypedMultiPolygon map_seen_through_glass() {
  return {testing::typed_polygon(testing::rectangle(0, 0, 8.2, 4, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))};
}

PlannerOptions options() { return testing::door_planner_options(); }

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
  const double y_without = testing::crossing_y(without.plan.best_candidate()->path, 4.1);
  EXPECT_LT(y_without, 1.5) << "without the keep-out the path crosses the glass";

  request.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(k.obstacles);
  const PlanResult with = compute_plan(request);
  ASSERT_TRUE(with.plan.ok) << with.plan.error;
  const GoalCandidate* goal = with.plan.best_candidate();
  ASSERT_NE(goal, nullptr) << "room B is reached through the door";
  EXPECT_GT(goal->position.x(), 4.2);
  const double y = testing::crossing_y(goal->path, 4.1);
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
  const auto none = without_keep_out(map, {});
  ASSERT_TRUE(none.ok) << none.error;
  EXPECT_EQ(mapping::vertex_count(none.polygons), mapping::vertex_count(map));
  const KeepOut far = parse_ok("POLYGON ((20 20, 21 20, 21 21, 20 21, 20 20))\n");
  const auto beside = without_keep_out(map, far.obstacles);
  ASSERT_TRUE(beside.ok) << beside.error;
  EXPECT_NEAR(mapping::area(beside.polygons), mapping::area(map), 1e-5);  // the overlay's grid
  const KeepOut half = parse_ok("POLYGON ((4 -1, 9 -1, 9 5, 4 5, 4 -1))\n");
  const auto cut = without_keep_out(map, half.obstacles);
  ASSERT_TRUE(cut.ok) << cut.error;
  EXPECT_NEAR(mapping::area(cut.polygons), 16.0, 1e-6);
}

// The map without the keep-out is computed once per map: a second plan on
// the same MAP takes it from the cache, a new map computes it again, and the
// plans are the ones planning without a cache gives.
TEST(KeepOut, TheMapWithoutTheKeepOutIsKeptPerMapAndChangesNoPlan) {
  const KeepOut k = parse_ok("LINESTRING (4.1 0, 4.1 1.5)\nLINESTRING (4.1 2.5, 4.1 4)\n");
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map_seen_through_glass());
  request.pose = Pose2{2.0, 0.7, 0.0};
  request.options = options();
  request.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(k.obstacles);
  PlanCache cache;
  const PlanResult first = compute_plan(request, &cache);
  const PlanResult again = compute_plan(request, &cache);
  EXPECT_EQ(cache.keep_out.misses(), 1);
  EXPECT_EQ(cache.keep_out.hits(), 1);
  const PlanResult uncached = compute_plan(request);
  for (const PlanResult* r : {&first, &again, &uncached}) {
    ASSERT_TRUE(r->plan.ok) << r->plan.error;
    ASSERT_NE(r->plan.best_candidate(), nullptr);
    EXPECT_FALSE(r->keep_out_failed);
  }
  auto xy = [](const PlanResult& r) {
    std::vector<std::pair<double, double>> out;
    for (const auto& p : r.plan.best_candidate()->path) out.emplace_back(p.x(), p.y());
    return out;
  };
  EXPECT_EQ(xy(again), xy(first));
  EXPECT_EQ(xy(uncached), xy(first));

  // A new MAP (the same polygons, a new message) and a new keep-out are computed anew.
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(*request.map);
  EXPECT_TRUE(compute_plan(request, &cache).plan.ok);
  request.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(*request.keep_out);
  EXPECT_TRUE(compute_plan(request, &cache).plan.ok);
  EXPECT_EQ(cache.keep_out.misses(), 3);
  EXPECT_EQ(cache.keep_out.hits(), 1);
}

// A keep-out the overlay refuses (an area given clockwise, which
// parse_keep_out never makes) fails the plan, flagged: it is never planned on
// the map without it.
TEST(KeepOut, APlanFailsWhenTheKeepOutCannotBeTakenOut) {
  mapping::TypedPolygon area;
  area.geometry.outer() = {Point(1, 1), Point(1, 2), Point(2, 2), Point(2, 1), Point(1, 1)};
  area.edge_types = {std::vector<E>(4, E::kObstacle)};
  const auto refused = without_keep_out(map_seen_through_glass(), {area});
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.error.find("degenerate"), std::string::npos) << refused.error;
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map_seen_through_glass());
  request.pose = Pose2{6.0, 2.0, 0.0};
  request.options = options();
  request.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(mapping::TypedMultiPolygon{area});
  PlanCache cache;
  for (PlanCache* c : {static_cast<PlanCache*>(nullptr), &cache, &cache}) {
    const PlanResult r = compute_plan(request, c);
    EXPECT_TRUE(r.keep_out_failed);
    EXPECT_FALSE(r.plan.ok);
    EXPECT_EQ(r.plan.best_candidate(), nullptr);
    EXPECT_NE(r.plan.error.find("keep-out"), std::string::npos) << r.plan.error;
  }
}

}  // namespace
}  // namespace pex::planning
