// The emulated mission of pex-bench-strategies and pex-bench-planning
// (mission_maps.hpp): what its robot does with a path through something.
#include <gtest/gtest.h>

#include "mission_maps.hpp"

namespace pex::bench {
namespace {

using mapping::Point;

// A 12 x 3 m corridor with a 4 cm post on its axis at x = 6, from its west end.
sim::World corridor_with_a_post() {
  std::string error;
  auto parsed = sim::parse_world(
      "START 1 1.5 0\n"
      "LINESTRING(0 0, 12 0, 12 3, 0 3, 0 0)\n"
      "POLYGON((5.98 1.48, 6.02 1.48, 6.02 1.52, 5.98 1.52, 5.98 1.48))\n",
      "corridor_with_a_post");
  return std::get<sim::World>(std::move(parsed));
}

// A plan with one candidate at `goal` looking at `frontier`, its path
// straight from the robot.
planning::Plan straight_to(const planning::Pose2& pose, const Point& goal, const Point& frontier) {
  planning::Plan plan;
  plan.ok = true;
  planning::GoalCandidate c;
  c.position = goal;
  c.frontier_point = frontier;
  c.reachable = true;
  c.path = {Point(pose.x_m, pose.y_m), goal};
  c.path_length_m = boost::geometry::distance(c.path[0], goal);
  c.cost = c.path_length_m;
  plan.candidates.push_back(c);
  plan.best = 0;
  return plan;
}

// One goal on the corridor's axis at goal_x (by default its east end,
// straight through the post); then none.
MissionPlanner through_the_post(double goal_x = 11.0) {
  return [goal_x](const mapping::TypedMultiPolygon&, const planning::Pose2& pose, const std::vector<Point>& blacklist,
                  const planning::GoalFocus*) {
    const Point goal(goal_x, 1.5);
    for (const auto& b : blacklist)
      if (boost::geometry::distance(b, goal) < 0.5) {
        planning::Plan none;
        none.ok = true;
        return none;
      }
    return straight_to(pose, goal, Point(12, 1.5));
  };
}

TEST(EmulatedMission, APathThroughAWallTheMapDoesNotHoldStopsShortOfIt) {
  const auto world = corridor_with_a_post();
  MissionMapsOptions o;
  o.max_goals = 5;
  o.robot_radius_m = 0.25;
  const auto maps = emulate_mission(world, o, through_the_post());
  ASSERT_TRUE(maps.error.empty()) << maps.error;
  EXPECT_EQ(maps.guard_stops, 1);
  EXPECT_TRUE(maps.done);
  // Stopped with the disk clear of the post: from x = 1 to at most 6 - 0.02 - 0.25.
  EXPECT_GT(maps.travelled_m, 4.0);
  EXPECT_LE(maps.travelled_m, 4.73 + 1e-9);
}

// A path whose last pose (not a whole scan step on) already touches the
// post: the travel counted ends at the pose before it, 4.5 m from START.
TEST(EmulatedMission, TheTravelCountedEndsAtTheLastClearPose) {
  const auto world = corridor_with_a_post();
  MissionMapsOptions o;
  o.max_goals = 5;
  o.robot_radius_m = 0.25;
  const auto maps = emulate_mission(world, o, through_the_post(5.74));
  ASSERT_TRUE(maps.error.empty()) << maps.error;
  EXPECT_EQ(maps.guard_stops, 1);
  EXPECT_NEAR(maps.travelled_m, 4.5, 1e-9);
}

TEST(EmulatedMission, WithoutARadiusThePathIsFollowedThroughIt) {
  const auto world = corridor_with_a_post();
  MissionMapsOptions o;
  o.max_goals = 5;
  const auto maps = emulate_mission(world, o, through_the_post());
  ASSERT_TRUE(maps.error.empty()) << maps.error;
  EXPECT_EQ(maps.guard_stops, 0);
  EXPECT_NEAR(maps.travelled_m, 10.0, 1e-9);
}

// With carry_goal the plans on the way carry the goal followed, as the
// explorer's follow plans do: a planner that offers the goal (x = 4, on the corridor's axis)
// only to a plan that follows it, and another goal (x = 2) to a plan that
// chooses anew, has the robot drive on to x = 4 and reach it. Without the
// focus the plan on the way would not match the goal, which would be left as
// seen for the other.
TEST(EmulatedMission, ThePlansOnTheWayCarryTheGoalFollowed) {
  const auto world = corridor_with_a_post();
  MissionMapsOptions o;
  o.max_goals = 1;
  o.replan_on_the_way = true;
  o.carry_goal = true;
  o.replan_step_m = 0.5;
  o.goal_match_radius_m = 0.5;
  int plans_with_focus = 0;
  const MissionPlanner planner = [&](const mapping::TypedMultiPolygon&, const planning::Pose2& pose,
                                     const std::vector<Point>&, const planning::GoalFocus* focus) {
    const Point goal = focus ? focus->goal : (pose.x_m < 1.5 ? Point(4, 1.5) : Point(2, 1.5));
    plans_with_focus += focus != nullptr;
    return straight_to(pose, goal, Point(goal.x() + 0.5, 1.5));
  };
  const auto maps = emulate_mission(world, o, planner);
  ASSERT_TRUE(maps.error.empty()) << maps.error;
  EXPECT_EQ(maps.goals, 1);
  EXPECT_EQ(maps.goals_seen, 0);  // reached, not left on the way
  EXPECT_GE(plans_with_focus, 4);  // 3 m at a plan every 0.5 m
  EXPECT_NEAR(maps.travelled_m, 3.0, 1e-9);
}

// The way in (emulate_mission's `way_in`, Mission::on_select_plan): the
// planner with the full margin offers only an approach point (x = 3) for a
// frontier at x = 8, and nothing once it is visited; the planner with the
// way in's margin, asked with that frontier as its focus, has a path to the
// frontier's own place (x = 7.5). The robot reaches the approach point, then
// goes in to x = 7.5, planning on the way with the way in's planner (the
// full margin's plans on the way would have no candidate there: the goal
// left as seen). Without `way_in` the mission ends at the approach point.
TEST(EmulatedMission, AnApproachPointReachedLeadsInWithTheWayInsPlanner) {
  const auto world = corridor_with_a_post();
  MissionMapsOptions o;
  o.max_goals = 5;
  o.replan_on_the_way = true;
  o.replan_step_m = 0.5;
  o.goal_match_radius_m = 1.0;
  const Point approach(3, 1), frontier(8, 1), inside(7.5, 1);
  auto blacklisted = [](const std::vector<Point>& blacklist, const Point& p) {
    for (const auto& b : blacklist)
      if (boost::geometry::distance(b, p) < 0.1) return true;
    return false;
  };
  const MissionPlanner with_margin = [&](const mapping::TypedMultiPolygon&, const planning::Pose2& pose,
                                         const std::vector<Point>& blacklist, const planning::GoalFocus*) {
    if (blacklisted(blacklist, approach)) {
      planning::Plan none;
      none.ok = true;
      return none;
    }
    auto plan = straight_to(pose, approach, frontier);
    plan.candidates[0].approach = true;
    return plan;
  };
  int way_in_plans = 0, focused_on_the_frontier = 0;
  const MissionPlanner way_in = [&](const mapping::TypedMultiPolygon&, const planning::Pose2& pose,
                                    const std::vector<Point>& blacklist, const planning::GoalFocus* focus) {
    ++way_in_plans;
    focused_on_the_frontier += focus && boost::geometry::distance(focus->frontier, frontier) < 0.1;
    planning::Plan plan;
    plan.ok = true;
    if (!blacklisted(blacklist, inside)) {
      plan = straight_to(pose, inside, frontier);
      plan.best = -1;  // the emulator chooses the way in itself
    }
    return plan;
  };
  const auto maps = emulate_mission(world, o, with_margin, way_in);
  ASSERT_TRUE(maps.error.empty()) << maps.error;
  EXPECT_TRUE(maps.done);
  EXPECT_EQ(maps.ways_in, 1);
  EXPECT_EQ(maps.goals, 2);
  EXPECT_EQ(maps.goals_seen, 0);  // reached, not left on the way
  EXPECT_GE(way_in_plans, 9);     // 4.5 m at a plan every 0.5 m, and the first
  EXPECT_EQ(focused_on_the_frontier, 1);  // the first, at the approach point
  const double to_approach = boost::geometry::distance(Point(1, 1.5), approach);
  EXPECT_NEAR(maps.travelled_m, to_approach + 4.5, 1e-9);

  const auto without = emulate_mission(world, o, with_margin);
  ASSERT_TRUE(without.error.empty()) << without.error;
  EXPECT_TRUE(without.done);
  EXPECT_EQ(without.ways_in, 0);
  EXPECT_EQ(without.goals, 1);
  EXPECT_NEAR(without.travelled_m, to_approach, 1e-9);
}

}  // namespace
}  // namespace pex::bench
