#include "planning/live_view.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "mapping/test_support.hpp"
#include "planning/exploration_planner.hpp"
#include "planning/mission.hpp"
#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

using mapping::EdgeType;
using mapping::Point;
using E = EdgeType;

// Two rooms, 4 x 4 m each, joined by a 1 m door at y = 1.5 .. 2.5 in the
// wall x = 4 .. 4.2. The world's walls, for the laser.
std::vector<mapping::testing::Wall> two_rooms_walls(bool door_open = true) {
  std::vector<mapping::testing::Wall> w;
  if (!door_open) w.push_back({Point(4.0, 1.5), Point(4.0, 2.5)});
  mapping::testing::add_box(w, 0, 0, 8.2, 4);
  w.push_back({Point(4.0, 0.0), Point(4.0, 1.5)});
  w.push_back({Point(4.0, 2.5), Point(4.0, 4.0)});
  w.push_back({Point(4.2, 0.0), Point(4.2, 1.5)});
  w.push_back({Point(4.2, 2.5), Point(4.2, 4.0)});
  w.push_back({Point(4.0, 1.5), Point(4.2, 1.5)});
  w.push_back({Point(4.0, 2.5), Point(4.2, 2.5)});
  return w;
}

// The planning map as a ghost band left it: both rooms mapped, but the door
// cut (the rooms are two polygons 0.2 m apart); room B's far side is a frontier.
mapping::TypedMultiPolygon map_with_the_door_closed() {
  using testing::typed_polygon;
  return {typed_polygon({{Point(0, 0), Point(4, 0), Point(4, 4), Point(0, 4)}, {}}),
          typed_polygon({{Point(4.2, 0), Point(8.2, 0), Point(8.2, 4), Point(4.2, 4)},
                         {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}})};
}

PlannerOptions options() { return testing::door_planner_options(); }

mapping::TypedMultiPolygon view_in(const std::vector<mapping::testing::Wall>& walls, const Pose2& robot,
                                   double range_m) {
  const mapping::testing::ScanSpec spec;
  const auto ranges = mapping::testing::cast_scan(walls, robot, spec);
  LiveViewOptions o;
  o.range_m = range_m;
  return live_view(ranges, spec.angle_min, spec.angle_increment, 0.05, robot, o);
}

mapping::TypedMultiPolygon view_from(const Pose2& robot, double range_m, bool door_open = true) {
  return view_in(two_rooms_walls(door_open), robot, range_m);
}

TEST(LiveView, TheNewestScanReopensADoorTheMapClosed) {
  const Pose2 robot{2.5, 2.0, 0.0};  // in room A, facing the door
  const auto map = map_with_the_door_closed();
  const Plan without = plan_exploration(map, robot, {}, options());
  ASSERT_TRUE(without.ok) << without.error;
  EXPECT_EQ(without.best_candidate(), nullptr) << "room B's frontier is cut off by the band";

  const auto live = view_from(robot, 4.0);
  ASSERT_FALSE(live.empty());
  // It opens, it adds no frontier: every edge is an obstacle edge.
  EXPECT_EQ(mapping::edge_length(live, E::kFrontier), 0.0);
  EXPECT_GT(mapping::edge_length(live, E::kObstacle), 0.0);

  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map);
  request.pose = robot;
  request.options = options();
  request.live_view = std::make_shared<const mapping::TypedMultiPolygon>(live);
  const PlanResult with = compute_plan(request);
  ASSERT_TRUE(with.plan.ok) << with.plan.error;
  const GoalCandidate* goal = with.plan.best_candidate();
  ASSERT_NE(goal, nullptr) << "the door is open in the live view";
  EXPECT_GT(goal->position.x(), 4.2);  // in room B
  // The path goes through the door.
  EXPECT_GT(testing::crossing_y(goal->path, 4.1), 1.5 + 0.27);
  EXPECT_LT(testing::crossing_y(goal->path, 4.1), 2.5 - 0.27);
}

// The two rooms as the map holds them with the wall between them glass
// (seen head-on: in the map) and the door open; room B's far side a frontier.
mapping::TypedMultiPolygon map_with_a_glass_wall() {
  using testing::typed_polygon;
  return {typed_polygon({{Point(0, 0), Point(4, 0), Point(4, 1.5), Point(4.2, 1.5), Point(4.2, 0), Point(8.2, 0),
                          Point(8.2, 4), Point(4.2, 4), Point(4.2, 2.5), Point(4, 2.5), Point(4, 4), Point(0, 4)},
                         {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier,
                          E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle}})};
}

TEST(LiveView, WhenStuckOnlyItOpensNoGlassTheMapHoldsButStillADoorTheMapShut) {
  // From low in room A the laser sees through the glass at a slant: the
  // view spans both rooms (its walls are the outer box only).
  const Pose2 robot{2.0, 0.7, 0.0};
  std::vector<mapping::testing::Wall> box;
  mapping::testing::add_box(box, 0, 0, 8.2, 4);
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map_with_a_glass_wall());
  request.pose = robot;
  request.options = options();
  request.live_view = std::make_shared<const mapping::TypedMultiPolygon>(view_in(box, robot, 6.0));
  ASSERT_FALSE(request.live_view->empty());

  // In every plan, the view reopens the glass: the path crosses it below the door.
  const PlanResult every = compute_plan(request);
  ASSERT_NE(every.plan.best_candidate(), nullptr) << every.plan.error;
  EXPECT_LT(testing::crossing_y(every.plan.best_candidate()->path, 4.1), 1.5);
  EXPECT_FALSE(every.live_view_used);

  // Only when stuck: the map has a way (the door), so the plan is the map's.
  request.live_view_when_stuck_only = true;
  const PlanResult stuck_only = compute_plan(request);
  const GoalCandidate* goal = stuck_only.plan.best_candidate();
  ASSERT_NE(goal, nullptr) << stuck_only.plan.error;
  EXPECT_GT(goal->position.x(), 4.2);
  EXPECT_GT(testing::crossing_y(goal->path, 4.1), 1.5 + 0.27);
  EXPECT_LT(testing::crossing_y(goal->path, 4.1), 2.5 - 0.27);
  EXPECT_FALSE(stuck_only.live_view_used);
  // A follow plan for that goal is the map's too: its goal has a path.
  const GoalFocus focus{goal->position, goal->frontier_point, 1.5};
  request.focus = focus;
  const PlanResult follow = compute_plan(request);
  EXPECT_FALSE(follow.live_view_used);
  EXPECT_TRUE(gives_a_way(follow.plan, &focus));

  // The door shut by a band and the laser seeing through it: no way on the
  // map alone, so the plan is made again with the view, through the door.
  const Pose2 facing{2.5, 2.0, 0.0};
  PlanRequest shut;
  shut.map = std::make_shared<const mapping::TypedMultiPolygon>(map_with_the_door_closed());
  shut.pose = facing;
  shut.options = options();
  shut.live_view = std::make_shared<const mapping::TypedMultiPolygon>(view_from(facing, 4.0));
  shut.live_view_when_stuck_only = true;
  const PlanResult opened = compute_plan(shut);
  EXPECT_TRUE(opened.live_view_used);
  const GoalCandidate* behind = opened.plan.best_candidate();
  ASSERT_NE(behind, nullptr) << opened.plan.error;
  EXPECT_GT(behind->position.x(), 4.2);
  EXPECT_GT(testing::crossing_y(behind->path, 4.1), 1.5 + 0.27);
  EXPECT_LT(testing::crossing_y(behind->path, 4.1), 2.5 - 0.27);
}

// Part of the window covered: the beams toward the door have no echo. The
// laser does not see through the door, so the view does not reopen it: those
// beams stop at the map's wall. Without the map they would open 3 m through it.
TEST(LiveView, ABlindSectorDoesNotReopenTheMapsWalls) {
  const mapping::testing::ScanSpec spec;
  const Pose2 robot{2.0, 2.0, 0.0};
  auto ranges = mapping::testing::cast_scan(two_rooms_walls(), robot, spec);
  for (std::size_t i = 0; i < ranges.size(); ++i)
    if (std::abs(spec.angle_min + spec.angle_increment * static_cast<double>(i)) < 0.4) ranges[i] = 0.0f;
  LiveViewOptions o;
  o.range_m = 3.0;
  const auto map = map_with_the_door_closed();
  auto farthest_x = [](const mapping::TypedMultiPolygon& view) {
    double x = -1e9;
    for (const auto& p : view)
      for (const auto& q : p.geometry.outer()) x = std::max(x, q.x());
    return x;
  };
  const auto stopped = live_view(ranges, spec.angle_min, spec.angle_increment, 0.05, robot, o, &map);
  ASSERT_FALSE(stopped.empty());
  EXPECT_LE(farthest_x(stopped), 4.0 + 1e-6);
  EXPECT_EQ(with_live_view(map, stopped).size(), 2u) << "the door stays cut";
  const auto open = live_view(ranges, spec.angle_min, spec.angle_increment, 0.05, robot, o, nullptr);
  EXPECT_GT(farthest_x(open), 4.5);
  o.no_return_stops_at_walls = false;
  EXPECT_GT(farthest_x(live_view(ranges, spec.angle_min, spec.angle_increment, 0.05, robot, o, &map)), 4.5);
}

// Beams known blind (mapping::BlindBeams) open nothing, with a map or
// without one: what lies along them is unknown, a wall not yet mapped too.
TEST(LiveView, ABlindBeamOpensNothing) {
  const mapping::testing::ScanSpec spec;
  const Pose2 robot{2.0, 2.0, 0.0};
  auto ranges = mapping::testing::cast_scan(two_rooms_walls(), robot, spec);
  std::vector<std::uint8_t> blind(ranges.size(), 0);
  for (std::size_t i = 0; i < ranges.size(); ++i)
    if (std::abs(spec.angle_min + spec.angle_increment * static_cast<double>(i)) < 0.4) {
      ranges[i] = 0.0f;
      blind[i] = 1;
    }
  LiveViewOptions o;
  o.range_m = 3.0;
  const auto map = map_with_the_door_closed();
  auto opens_ahead = [](const mapping::TypedMultiPolygon& view) {
    for (const auto& p : view)
      if (mapping::bg::within(mapping::Point(3.5, 2.0), p.geometry)) return true;
    return false;
  };
  for (const mapping::TypedMultiPolygon* with : {&map, static_cast<const mapping::TypedMultiPolygon*>(nullptr)}) {
    const auto view = live_view(ranges, spec.angle_min, spec.angle_increment, 0.05, robot, o, with, blind);
    ASSERT_FALSE(view.empty()) << "the beams that see still give a view";
    EXPECT_FALSE(opens_ahead(view)) << (with ? "with" : "without") << " the map";
    EXPECT_TRUE(opens_ahead(live_view(ranges, spec.angle_min, spec.angle_increment, 0.05, robot, o, with)))
        << "not known blind, the beams open 1.5 m ahead (" << (with ? "with" : "without") << " the map)";
  }
}

TEST(LiveView, AWallTheLaserSeesStaysClosed) {
  // The same map, but the door really is shut: the laser sees the wall, the
  // live view ends at it, with the band of its own returns, and nothing opens.
  const Pose2 robot{2.5, 2.0, 0.0};
  const auto live = view_from(robot, 4.0, /*door_open=*/false);
  ASSERT_FALSE(live.empty());
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map_with_the_door_closed());
  request.pose = robot;
  request.options = options();
  request.live_view = std::make_shared<const mapping::TypedMultiPolygon>(live);
  const PlanResult result = compute_plan(request);
  ASSERT_TRUE(result.plan.ok) << result.plan.error;
  EXPECT_EQ(result.plan.best_candidate(), nullptr);
}

// A frontier the laser sees past now, before the mapper has the scan: the
// live view covers it, but it stays a goal (only the map says what is
// explored; a covered frontier that vanished could end the mission early).
TEST(LiveView, AFrontierTheViewCoversStaysAGoal) {
  const Pose2 robot{2.5, 2.0, 0.0};
  // The map: a hall's west part with its east side (x = 4) a frontier; the
  // hall goes on to x = 8.2, and the laser sees across x = 4 all along it.
  using testing::typed_polygon;
  const mapping::TypedMultiPolygon map{
      typed_polygon({{Point(0, 0), Point(4, 0), Point(4, 4), Point(0, 4)},
                     {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}})};
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map);
  request.pose = robot;
  request.options = options();
  std::vector<mapping::testing::Wall> hall;
  mapping::testing::add_box(hall, 0, 0, 8.2, 4);
  const auto live = view_in(hall, robot, 3.0);
  ASSERT_GT(mapping::area(live), 0.0);
  // The view covers the frontier edge (x = 4 for y in 0.5 .. 3.5 at least).
  ASSERT_TRUE(boost::geometry::within(Point(4.0, 2.0), mapping::geometry_of(live)));
  request.live_view = std::make_shared<const mapping::TypedMultiPolygon>(live);
  const PlanResult result = compute_plan(request);
  ASSERT_TRUE(result.plan.ok) << result.plan.error;
  ASSERT_NE(result.plan.best_candidate(), nullptr);
  EXPECT_NEAR(result.plan.best_candidate()->frontier_point.x(), 4.0, 1e-6);
}

TEST(LiveView, OffOrWithoutAPolygonItIsEmpty) {
  EXPECT_TRUE(view_from(Pose2{2.5, 2.0, 0.0}, 0.0).empty());
  const std::vector<float> one_beam{1.0f};
  LiveViewOptions o;
  o.range_m = 3.0;
  EXPECT_TRUE(live_view(one_beam, 0.0, 0.01, 0.05, geometry::Pose2{}, o).empty());
  // And an empty live view leaves the map as it is.
  const auto map = map_with_the_door_closed();
  EXPECT_EQ(mapping::vertex_count(with_live_view(map, {})), mapping::vertex_count(map));
}

}  // namespace
}  // namespace pex::planning
