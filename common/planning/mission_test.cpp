#include "planning/mission.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

using E = mapping::EdgeType;
using testing::rectangle;
using testing::rectangle_hole;
using testing::typed_polygon;

constexpr std::int64_t kSecond = 1'000'000;

// A corridor 20 x 3 m, frontier at the chosen ends.
mapping::TypedMultiPolygon corridor(bool left_frontier, bool right_frontier) {
  return {typed_polygon(rectangle(0, 0, 20, 3,
                                  {E::kObstacle, right_frontier ? E::kFrontier : E::kObstacle, E::kObstacle,
                                   left_frontier ? E::kFrontier : E::kObstacle}))};
}

MissionOptions test_options() {
  MissionOptions o;
  o.planner.cspace.robot_radius_m = 0.3;
  o.planner.turn_cost_m_per_rad = 0.0;
  o.pose_timeout_us = kSecond;
  o.map_timeout_us = 10 * kSecond;
  o.replan_period_us = kSecond;
  o.progress_timeout_us = 5 * kSecond;
  return o;
}

TEST(Mission, IdleUntilItHasAMapAndAPose) {
  Mission m(test_options());
  auto out = step_with_inline_planning(m, 0);
  EXPECT_EQ(out.phase, Phase::kIdle);
  EXPECT_EQ(out.command.v_mps, 0.0);
  m.on_pose(Pose2{5, 1.5, 0}, 0);
  out = step_with_inline_planning(m, 100'000);
  EXPECT_EQ(out.phase, Phase::kIdle);
  EXPECT_NE(out.status.find("map"), std::string::npos);
}

TEST(Mission, SelectsTheNearestGoalAndDrivesTowardIt) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{15, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  ASSERT_TRUE(out.goal.has_value());
  EXPECT_NEAR(out.goal->x(), 20 - 0.35, 0.01);
  EXPECT_EQ(out.goal_candidates, 1);
  EXPECT_EQ(out.plans, 1);
  ASSERT_GE(out.path.size(), 2u);
  m.on_pose(Pose2{15, 1.5, 0}, 100'000);
  out = step_with_inline_planning(m, 100'000);
  EXPECT_GT(out.command.v_mps, 0.0);
  EXPECT_NEAR(out.explored_area_m2, 60.0, 1e-9);
}

// On the corridor open at both ends, from (14, 1.5): the right end is chosen
// and reached (the robot put there at 200 ms). The map is stamped at 0, its
// newest scan at `map_scan_utime`. Returns the goal reached.
Point reach_the_right_end(Mission& m, std::int64_t map_scan_utime = -1) {
  m.on_map(corridor(true, true), 0, map_scan_utime);
  m.on_pose(Pose2{14, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  EXPECT_EQ(out.phase, Phase::kMoving);
  const Point goal = out.goal.value_or(Point(19.7, 1.5));
  EXPECT_GT(goal.x(), 10.0);  // the right end is nearer
  m.on_pose(Pose2{goal.x() - 0.05, goal.y(), 0}, 200'000);
  out = step_with_inline_planning(m, 200'000);
  EXPECT_EQ(out.phase, Phase::kSelecting);
  EXPECT_NE(out.status.find("reached"), std::string::npos);
  EXPECT_EQ(out.command.v_mps, 0.0);
  return goal;
}

TEST(Mission, GoalReachedWaitsForANewerMapThenTakesTheNextGoal) {
  Mission m(test_options());
  const Point first = reach_the_right_end(m);
  ASSERT_EQ(m.visited_goals().size(), 1u);
  // The same map again: it waits.
  auto out = step_with_inline_planning(m, 1'500'000);
  EXPECT_EQ(out.phase, Phase::kSelecting);
  EXPECT_FALSE(out.plan_request.has_value());
  // A newer map in which the right frontier is still there (the laser could
  // not clear it): the visited goal is not offered again, the left end is.
  m.on_map(corridor(true, true), 1'600'000);
  m.on_pose(Pose2{first.x() - 0.05, first.y(), 0}, 1'600'000);
  out = step_with_inline_planning(m, 1'700'000);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(out.goal->x(), 1.0);
}

// After a goal, a newer map is not enough when its newest scan is older than
// the arrival: the look at the frontier is not in it yet. It waits for one
// that has it, at most three replan periods (a mapper that never sends one).
TEST(Mission, GoalReachedWaitsForAMapWithAScanFromTheGoal) {
  Mission m(test_options());
  const Point first = reach_the_right_end(m, 0);
  // A newer map, but built from scans before the arrival: still waiting.
  m.on_map(corridor(true, true), 1'000'000, 150'000);
  m.on_pose(Pose2{first.x() - 0.05, first.y(), 0}, 1'100'000);
  auto out = step_with_inline_planning(m, 1'100'000);
  EXPECT_EQ(out.phase, Phase::kSelecting);
  EXPECT_FALSE(out.plan_request.has_value());
  EXPECT_NE(out.status.find("waiting for the map"), std::string::npos) << out.status;
  // One with a scan from the goal: the next goal.
  m.on_map(corridor(true, true), 2'000'000, 1'900'000);
  m.on_pose(Pose2{first.x() - 0.05, first.y(), 0}, 2'000'000);
  out = step_with_inline_planning(m, 2'000'000);
  EXPECT_EQ(out.phase, Phase::kMoving) << out.status;

  // The bound: maps whose scans never get newer stop holding it after 3 s.
  Mission n(test_options());
  const Point reached = reach_the_right_end(n, 0);
  n.on_map(corridor(true, true), 2'000'000, 0);
  n.on_pose(Pose2{reached.x() - 0.05, reached.y(), 0}, 2'000'000);
  out = step_with_inline_planning(n, 2'000'000);
  EXPECT_EQ(out.phase, Phase::kSelecting);
  n.on_map(corridor(true, true), 3'300'000, 0);
  n.on_pose(Pose2{19.0, 1.5, 0}, 3'300'000);
  out = step_with_inline_planning(n, 3'300'000);
  EXPECT_EQ(out.phase, Phase::kMoving) << out.status;
}

// A restarted explorer takes the mission up: visited goals stay visited, the
// distance and the mission clock go on from where they were.
TEST(Mission, ACheckpointTakesTheMissionUpAfterARestart) {
  Mission m(test_options());
  m.on_map(corridor(true, true), 0);
  m.on_pose(Pose2{14, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  const Point goal = *out.goal;
  std::int64_t t = 0;
  for (double x = 14.0; x < goal.x() - 0.05; x += 0.1) {  // drives there
    t += 100'000;
    m.on_pose(Pose2{x, 1.5, 0}, t);
  }
  m.on_pose(Pose2{goal.x() - 0.05, goal.y(), 0}, t + 100'000);
  out = step_with_inline_planning(m, t + 100'000);
  ASSERT_EQ(m.visited_goals().size(), 1u);

  std::string why;
  const auto text = to_text(m.checkpoint());
  const auto restored = checkpoint_from_text(text, &why);
  ASSERT_TRUE(restored) << why;
  Mission n(test_options());
  n.restore(*restored);
  EXPECT_EQ(n.visited_goals().size(), 1u);
  EXPECT_EQ(n.blacklist().size(), m.blacklist().size());
  EXPECT_EQ(n.goal_outcomes().reached, 1);
  // It goes on: the visited right end is not offered again, the left one is;
  // the mission clock counts from the first start.
  n.on_map(corridor(true, true), 10'000'000);
  n.on_pose(Pose2{19.0, 1.5, 0}, 10'000'000);
  out = step_with_inline_planning(n, 10'000'000);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(out.goal->x(), 1.0);
  EXPECT_NEAR(out.mission_time_s, 10.0, 1e-9);
  EXPECT_NEAR(out.distance_travelled_m, restored->travelled_m + 0.0, 1e-9);  // no pose jump counted at the restart
  EXPECT_GT(restored->travelled_m, 0.0);

  // A stopped mission stays stopped; a paused one stays paused.
  auto stopped = *restored;
  stopped.phase = Phase::kStopped;
  Mission s(test_options());
  s.restore(*checkpoint_from_text(to_text(stopped)));
  s.on_map(corridor(true, true), 0);
  s.on_pose(Pose2{5, 1.5, 0}, 0);
  EXPECT_EQ(step_with_inline_planning(s, 0).phase, Phase::kStopped);
  auto paused = *restored;
  paused.phase = Phase::kPaused;
  Mission p(test_options());
  p.restore(paused);
  p.on_map(corridor(true, true), 0);
  p.on_pose(Pose2{5, 1.5, 0}, 0);
  EXPECT_EQ(step_with_inline_planning(p, 0).phase, Phase::kPaused);
  EXPECT_EQ(p.on_command(MissionCommand::kResume, 100'000), "");
  EXPECT_EQ(step_with_inline_planning(p, 100'000).phase, Phase::kMoving);
}

TEST(Mission, ABrokenCheckpointIsRefusedWithAReason) {
  std::string why;
  EXPECT_FALSE(checkpoint_from_text("", &why));
  EXPECT_NE(why.find("not a mission checkpoint"), std::string::npos) << why;
  const std::string good = to_text(MissionCheckpoint{});
  ASSERT_TRUE(checkpoint_from_text(good, &why)) << why;
  // Cut short (power lost while writing): no "end" line.
  EXPECT_FALSE(checkpoint_from_text(good.substr(0, good.size() - 4), &why));
  EXPECT_NE(why.find("incomplete"), std::string::npos) << why;
  EXPECT_FALSE(checkpoint_from_text("polyexplore-mission 1\nvisited 1 nan\nend\n", &why));
  EXPECT_NE(why.find("bad value for 'visited'"), std::string::npos) << why;
  EXPECT_FALSE(checkpoint_from_text("polyexplore-mission 1\nphase 42\nend\n", &why));
  EXPECT_FALSE(checkpoint_from_text("polyexplore-mission 1\nwhatever 1\nend\n", &why));
  EXPECT_NE(why.find("unknown key"), std::string::npos) << why;
  EXPECT_FALSE(checkpoint_from_text("polyexplore-mission 1\noutcomes 1 2 3 4 x\nend\n", &why));
  EXPECT_NE(why.find("bad value for 'outcomes'"), std::string::npos) << why;
}

TEST(Mission, ACheckpointKeepsEveryGoalOutcome) {
  MissionCheckpoint c;
  c.outcomes = GoalOutcomes{1, 2, 3, 4, 5, 6};
  std::string why;
  const auto back = checkpoint_from_text(to_text(c), &why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(back->outcomes.reached, 1);
  EXPECT_EQ(back->outcomes.seen, 2);
  EXPECT_EQ(back->outcomes.blocked, 3);
  EXPECT_EQ(back->outcomes.no_progress, 4);
  EXPECT_EQ(back->outcomes.overdue, 5);
  EXPECT_EQ(back->outcomes.came_back, 6);
  // A checkpoint written before the overdue count has four.
  const auto old = checkpoint_from_text("polyexplore-mission 1\noutcomes 1 2 3 4\nend\n", &why);
  ASSERT_TRUE(old) << why;
  EXPECT_EQ(old->outcomes.no_progress, 4);
  EXPECT_EQ(old->outcomes.overdue, 0);
  EXPECT_EQ(old->outcomes.came_back, 0);
  // One written before the came-back count has five.
  const auto five = checkpoint_from_text("polyexplore-mission 1\noutcomes 1 2 3 4 5\nend\n", &why);
  ASSERT_TRUE(five) << why;
  EXPECT_EQ(five->outcomes.overdue, 5);
  EXPECT_EQ(five->outcomes.came_back, 0);
}

TEST(Mission, AtTheGoalItTurnsToFaceTheFrontierBeforeItCountsAsReached) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{14, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  const Point goal = *out.goal;
  // At the goal, but facing west (away from the frontier at x = 20).
  m.on_pose(Pose2{goal.x() - 0.05, goal.y(), std::numbers::pi}, 200'000);
  out = step_with_inline_planning(m, 200'000);
  EXPECT_EQ(out.phase, Phase::kMoving);
  EXPECT_EQ(out.command.v_mps, 0.0);
  EXPECT_NE(out.command.omega_radps, 0.0);
  EXPECT_EQ(m.goal_outcomes().reached, 0);
  // Facing it: reached.
  m.on_pose(Pose2{goal.x() - 0.05, goal.y(), 0.2}, 300'000);
  out = step_with_inline_planning(m, 300'000);
  EXPECT_EQ(out.phase, Phase::kSelecting);
  EXPECT_EQ(m.goal_outcomes().reached, 1);
}

TEST(Mission, DoneWhenNoFrontierIsLeftOnTwoMaps) {
  Mission m(test_options());
  m.on_map(corridor(false, false), 0);
  m.on_pose(Pose2{5, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  EXPECT_EQ(out.phase, Phase::kSelecting);  // one map is not enough
  out = step_with_inline_planning(m, 2 * kSecond);                // the same map again does not count twice
  EXPECT_EQ(out.phase, Phase::kSelecting);
  m.on_map(corridor(false, false), 2'100'000);
  m.on_pose(Pose2{5, 1.5, 0}, 2'100'000);
  out = step_with_inline_planning(m, 2'200'000);
  ASSERT_EQ(out.phase, Phase::kDone);
  EXPECT_NE(out.status.find("no frontier left"), std::string::npos);
  // DONE is final: the robot stays stopped.
  m.on_map(corridor(true, true), 3'000'000);
  out = step_with_inline_planning(m, 3'100'000);
  EXPECT_EQ(out.phase, Phase::kDone);
  EXPECT_EQ(out.command.v_mps, 0.0);
  EXPECT_EQ(out.command.omega_radps, 0.0);
}

TEST(Mission, DoneWhenEveryFrontierLeftWasVisited) {
  // The robot gets to the right end's goal facing it, but the maps keep the
  // frontier (the laser cannot clear it): nothing more to see by driving.
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{14, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  const Point goal = *out.goal;
  m.on_pose(Pose2{goal.x() - 0.05, goal.y(), 0}, 200'000);
  step_with_inline_planning(m, 200'000);
  for (std::int64_t t = 1; t <= 3; ++t) {
    m.on_map(corridor(false, true), t * kSecond);
    m.on_pose(Pose2{goal.x() - 0.05, goal.y(), 0}, t * kSecond);
    out = step_with_inline_planning(m, t * kSecond + 1);
  }
  EXPECT_EQ(out.phase, Phase::kDone) << out.status;
  EXPECT_NE(out.status.find("visited"), std::string::npos) << out.status;
  ASSERT_EQ(out.frontiers.size(), 1u);
  EXPECT_EQ(out.frontiers[0].reason, FrontierReason::kVisited);
}

TEST(Mission, GoalGoneOnANewMapChoosesAnother) {
  Mission m(test_options());
  m.on_map(corridor(true, true), 0);
  m.on_pose(Pose2{14, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  EXPECT_GT(out.goal->x(), 10.0);
  const Point right_goal = *out.goal;
  // The right end turned out to be a wall. One map without it: the goal is
  // kept (a map can drop a frontier and show it again in the next).
  m.on_map(corridor(true, false), 900'000);
  m.on_pose(Pose2{14.5, 1.5, 0}, 1'000'000);
  out = step_with_inline_planning(m, 1'000'000);  // replan period reached
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(distance(*out.goal, right_goal), 0.01);
  EXPECT_EQ(m.goal_outcomes().seen, 0);
  // A newer map without it either: seen; the other end is chosen.
  m.on_map(corridor(true, false), 1'900'000);
  m.on_pose(Pose2{14.8, 1.5, 0}, 2'000'000);
  out = step_with_inline_planning(m, 2'000'000);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(out.goal->x(), 1.0);
  EXPECT_EQ(m.goal_outcomes().seen, 1);
  EXPECT_TRUE(m.blacklist().empty());  // explored, not given up
}

// A frontier the maps show and drop by turns (b30, intel greedy: one place
// chosen six times, 5-10 m each, among trips to others): the second time a
// goal there is seen, it is given up, and the robot goes elsewhere.
TEST(Mission, AGoalSeenWhereOneWasSeenBeforeIsGivenUp) {
  Mission m(test_options());
  std::int64_t t = 0;
  // Maps and poses at t, a step at t + 100 ms.
  auto at = [&](const mapping::TypedMultiPolygon& map, double x) {
    m.on_map(map, t);
    m.on_pose(Pose2{x, 1.5, 0}, t + 100'000);
    t += kSecond;
    return step_with_inline_planning(m, t - kSecond + 100'000);
  };
  auto out = at(corridor(true, true), 14.0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  const Point right_goal = *out.goal;
  ASSERT_GT(right_goal.x(), 15.0);
  // The right end gone from two maps in a row: seen, the left end chosen.
  at(corridor(true, false), 14.0);
  out = at(corridor(true, false), 14.0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(out.goal->x(), 5.0);
  EXPECT_EQ(m.goal_outcomes().seen, 1);
  // The maps turn: the right end is back and the left one gone (seen too),
  // so the right end is chosen again.
  at(corridor(false, true), 14.0);
  out = at(corridor(false, true), 14.0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  ASSERT_LT(distance(*out.goal, right_goal), 0.5) << out.status;
  EXPECT_EQ(m.goal_outcomes().seen, 2);
  EXPECT_TRUE(m.blacklist().empty());
  // Gone again: seen where it was seen before, given up there.
  at(corridor(true, false), 14.0);
  out = at(corridor(true, false), 14.0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(out.goal->x(), 5.0);
  EXPECT_EQ(m.goal_outcomes().seen, 2);
  EXPECT_EQ(m.goal_outcomes().came_back, 1);
  // Back once more: blacklisted, so the robot keeps to the left end.
  out = at(corridor(true, true), 14.0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(out.goal->x(), 5.0);
  ASSERT_FALSE(m.blacklist().empty());
  EXPECT_LT(distance(m.blacklist().back(), right_goal), 0.01);
}

// At the end of a mission a frontier behind a passage SLAM's corrections
// open and close drops out of one map and comes back in the next. With no
// other goal in reach, the goal is kept (and driven to) until a newer map
// confirms it gone; one map without it is not "seen".
TEST(Mission, AGoalGoneFromOneMapWithNothingElseInReachIsKeptUntilANewerMapConfirms) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{14, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  const Point goal = *out.goal;
  EXPECT_GT(goal.x(), 15.0);
  // One map without the frontier: still moving to the goal, on its path.
  m.on_map(corridor(false, false), 900'000);
  m.on_pose(Pose2{14.3, 1.5, 0}, kSecond);
  out = step_with_inline_planning(m, kSecond);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(distance(*out.goal, goal), 0.01);
  EXPECT_GT(out.command.v_mps, 0.0);
  // It comes back: the same goal, nothing counted.
  m.on_map(corridor(false, true), 1'900'000);
  m.on_pose(Pose2{14.6, 1.5, 0}, 2 * kSecond);
  out = step_with_inline_planning(m, 2 * kSecond);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(distance(*out.goal, goal), 0.01);
  EXPECT_EQ(m.goal_outcomes().seen, 0);
  // Gone on one map and on the next: seen.
  for (int k = 3; k <= 4; ++k) {
    m.on_map(corridor(false, false), k * kSecond - 100'000);
    m.on_pose(Pose2{14.3 + 0.3 * k, 1.5, 0}, k * kSecond);
    out = step_with_inline_planning(m, k * kSecond);
  }
  EXPECT_EQ(m.goal_outcomes().seen, 1);
  EXPECT_EQ(out.phase, Phase::kSelecting) << out.status;
  EXPECT_FALSE(out.goal.has_value());
}

TEST(Mission, BlockedGoalIsBlacklisted) {
  // Without approach points: the frontier behind the gap would otherwise be
  // approached (looked at through the gap) instead of being blocked.
  MissionOptions o = test_options();
  o.planner.approach_range_m = 0.0;
  Mission m(o);
  m.on_map(corridor(true, true), 0);
  m.on_pose(Pose2{12, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  ASSERT_GT(out.goal->x(), 10.0);
  // A wall across the corridor at x = 16 with a 0.4 m gap: the right end is
  // still a frontier but the robot cannot get there.
  testing::RingSpec blocked{{Point(0, 0), Point(16, 0), Point(16, 1.3), Point(16.2, 1.3), Point(16.2, 0), Point(20, 0),
                             Point(20, 3), Point(16.2, 3), Point(16.2, 1.7), Point(16, 1.7), Point(16, 3), Point(0, 3)},
                            {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier,
                             E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier}};
  m.on_map({typed_polygon(blocked)}, 900'000);
  m.on_pose(Pose2{12.5, 1.5, 0}, 1'000'000);
  out = step_with_inline_planning(m, 1'000'000);
  // No path on one map: kept, on the path it had, until a newer map confirms.
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_GT(out.goal->x(), 16.0);
  EXPECT_NE(out.status.find("newer map confirms"), std::string::npos) << out.status;
  EXPECT_TRUE(m.blacklist().empty());
  EXPECT_EQ(m.goal_outcomes().blocked, 0);
  // No path on the newer map either.
  m.on_map({typed_polygon(blocked)}, 1'900'000);
  m.on_pose(Pose2{12.9, 1.5, 0}, 2'000'000);
  out = step_with_inline_planning(m, 2'000'000);
  // Given up and blacklisted, and (planning inline) the next goal chosen at once.
  ASSERT_EQ(m.blacklist().size(), 1u);
  EXPECT_GT(m.blacklist()[0].x(), 16.0);
  EXPECT_EQ(m.goal_outcomes().blocked, 1);
  EXPECT_EQ(m.goal_outcomes().reached, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(out.goal->x(), 1.0);
}

// The plan with no path to any candidate (what a newer map that blocks the goal gives).
void take_the_paths_away(PlanResult& result) {
  for (auto& c : result.plan.candidates) {
    c.reachable = false;
    c.path.clear();
  }
  result.plan.best = -1;
}

// A plan of the followed goal without a path, then one with it on the same
// map (another pose, another live view): kept, nothing counted, and the
// next map without a path starts the wait afresh.
TEST(Mission, AGoalWithoutAPathOnOnePlanIsKeptWhenTheNextHasOne) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  const Point goal = *out.goal;
  // The plan asked for at t (a new map first when map_utime >= 0), without its paths when pathless.
  auto replan = [&](std::int64_t map_utime, std::int64_t t, bool pathless) {
    if (map_utime >= 0) m.on_map(corridor(false, true), map_utime);
    m.on_pose(Pose2{10.2, 1.5, 0}, t);
    auto o = m.step(t);
    EXPECT_TRUE(o.plan_request.has_value()) << o.status;
    if (!o.plan_request) return o;
    PlanResult result = compute_plan(*o.plan_request);
    if (pathless) {
      take_the_paths_away(result);
    }
    m.on_plan(result, t + 1);
    return m.step(t + 2);
  };
  out = replan(900'000, kSecond, true);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_NE(out.status.find("newer map confirms"), std::string::npos) << out.status;
  out = replan(-1, 2 * kSecond, false);  // the same map, a path again
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_LT(distance(*out.goal, goal), 0.01);
  out = replan(2'900'000, 3 * kSecond, true);  // a newer map without one: waits again
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_EQ(m.goal_outcomes().blocked, 0);
  EXPECT_TRUE(m.blacklist().empty());
  out = replan(3'900'000, 4 * kSecond, true);  // and the next map confirms
  EXPECT_EQ(m.goal_outcomes().blocked, 1);
  ASSERT_EQ(m.blacklist().size(), 1u);
  EXPECT_LT(distance(m.blacklist()[0], goal), 0.01);
}

// A mission set off towards the corridor's right end, and the plan it asks
// for a second later (computed): the goal, the frontier it follows, and the
// candidate of that plan at the goal (`same`, -1: none, or no plan asked).
struct FollowedGoalReplan {
  std::optional<Point> goal, frontier;
  PlanResult result;
  int same = -1;
};
FollowedGoalReplan follow_then_replan(Mission& m) {
  FollowedGoalReplan r;
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  if (out.phase != Phase::kMoving || !out.goal) return r;
  r.goal = *out.goal;
  m.on_map(corridor(false, true), kSecond);
  m.on_pose(Pose2{10.5, 1.5, 0}, kSecond);
  out = m.step(kSecond + 1);  // replan period reached
  if (!out.plan_request) return r;
  if (out.plan_request->focus) r.frontier = out.plan_request->focus->frontier;
  r.result = compute_plan(*out.plan_request);
  for (std::size_t i = 0; i < r.result.plan.candidates.size(); ++i)
    if (r.result.plan.candidates[i].reachable && distance(r.result.plan.candidates[i].position, *r.goal) < 0.5)
      r.same = static_cast<int>(i);
  return r;
}

// `c` listed first among the plan's candidates.
void list_first(PlanResult& result, GoalCandidate c) {
  result.plan.candidates.insert(result.plan.candidates.begin(), std::move(c));
  if (result.plan.best >= 0) ++result.plan.best;
}

// In clutter several candidates match the goal being followed; one without
// a path nearer the goal (a sliver past a chair leg) does not block it while
// another that matches has a path.
TEST(Mission, AnUnreachableMatchDoesNotBlockAGoalAReachableMatchStillHas) {
  Mission m(test_options());
  auto [goal, frontier, result, same] = follow_then_replan(m);
  ASSERT_GE(same, 0);
  GoalCandidate sliver = result.plan.candidates[static_cast<std::size_t>(same)];
  sliver.position = *goal;  // nearer the goal than any other
  sliver.reachable = false;
  sliver.path.clear();
  list_first(result, sliver);
  m.on_plan(result, kSecond + 2);
  auto out = m.step(kSecond + 3);
  EXPECT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_EQ(m.goal_outcomes().blocked, 0);
  EXPECT_TRUE(m.blacklist().empty());
  // With no reachable match left, on two maps, the goal is blocked.
  for (int k = 2; k <= 3; ++k) {
    EXPECT_EQ(m.goal_outcomes().blocked, 0);
    m.on_map(corridor(false, true), k * kSecond);
    m.on_pose(Pose2{11, 1.5, 0}, k * kSecond);
    out = m.step(k * kSecond + 4);
    ASSERT_TRUE(out.plan_request.has_value());
    result = compute_plan(*out.plan_request);
    take_the_paths_away(result);
    m.on_plan(result, k * kSecond + 5);
    m.step(k * kSecond + 6);
  }
  EXPECT_EQ(m.goal_outcomes().blocked, 1);
}

// Frontiers seen from one place share its approach point. The goal followed
// keeps its own frontier when a plan lists another frontier at the same
// point first: else the robot at the goal turns to face each in turn.
TEST(Mission, AFollowedGoalKeepsItsFrontierWhenAnotherSharesItsPlace) {
  Mission m(test_options());
  auto [goal, frontier, result, same] = follow_then_replan(m);
  ASSERT_TRUE(frontier.has_value());
  ASSERT_GE(same, 0);
  ASSERT_LT(distance(result.plan.candidates[static_cast<std::size_t>(same)].frontier_point, *frontier), 0.01);
  GoalCandidate other = result.plan.candidates[static_cast<std::size_t>(same)];
  other.position = *goal;  // the very place of the goal
  other.frontier_point = Point(frontier->x(), frontier->y() + 1.2);  // another frontier seen from there
  list_first(result, other);
  m.on_plan(result, kSecond + 2);
  auto out = m.step(kSecond + 3);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  // The next plan request follows the goal's own frontier.
  m.on_map(corridor(false, true), 2 * kSecond);
  m.on_pose(Pose2{10.6, 1.5, 0}, 2 * kSecond);
  out = m.step(2 * kSecond + 4);
  ASSERT_TRUE(out.plan_request.has_value() && out.plan_request->focus.has_value()) << out.status;
  EXPECT_LT(distance(out.plan_request->focus->frontier, *frontier), 0.01);
}

// Goals blocked by a newer map (no path any more) are given up and
// blacklisted, but they are not failures of the robot: at the end of a
// mission in clutter the last goals often lie behind passages SLAM's
// corrections open and close (intel, greedy: FAILED at coverage 0.993 after
// five of them in a row). Only goals without progress, the robot stuck, make
// the mission FAILED.
TEST(Mission, GoalsBlockedInARowDoNotFailTheMission) {
  MissionOptions o = test_options();
  o.max_consecutive_failures = 2;
  Mission m(o);
  // The goal followed finds no path at its next plans, on two newer maps
  // (t and t + 1 s; the robot at its start).
  auto block_followed_goal = [&](std::int64_t t) {
    for (const std::int64_t at : {t, t + kSecond}) {
      m.on_map(corridor(true, true), at);
      m.on_pose(Pose2{10, 1.5, 0}, at);
      auto out = m.step(at + 1);  // replan period reached
      ASSERT_TRUE(out.plan_request.has_value()) << out.status;
      PlanResult result = compute_plan(*out.plan_request);
      take_the_paths_away(result);
      m.on_plan(result, at + 2);
    }
  };
  m.on_map(corridor(true, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  const Point first = *out.goal;
  block_followed_goal(kSecond);
  out = step_with_inline_planning(m, 2 * kSecond + 3);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;  // the other end
  EXPECT_GT(distance(*out.goal, first), 5.0);
  block_followed_goal(4 * kSecond);
  out = m.step(5 * kSecond + 3);
  EXPECT_EQ(m.goal_outcomes().blocked, 2);
  EXPECT_EQ(m.blacklist().size(), 2u);
  EXPECT_NE(out.phase, Phase::kFailed) << out.status;
}

TEST(Mission, FailsAfterRepeatedGoalsWithoutProgress) {
  MissionOptions o = test_options();
  o.max_consecutive_failures = 2;
  Mission m(o);
  // A room with frontiers on three sides; the robot never moves (wheels stuck).
  m.on_map({typed_polygon(rectangle(0, 0, 20, 20, {E::kFrontier, E::kFrontier, E::kFrontier, E::kObstacle}))}, 0);
  Phase phase = Phase::kIdle;
  std::string status;
  for (std::int64_t t = 0; t <= 30 * kSecond; t += 100'000) {
    m.on_pose(Pose2{3, 10, 0}, t);
    if (t % (5 * kSecond) == 0) m.on_map({typed_polygon(rectangle(0, 0, 20, 20, {E::kFrontier, E::kFrontier,
                                                                                    E::kFrontier, E::kObstacle}))},
                                         t);
    const auto out = step_with_inline_planning(m, t);
    phase = out.phase;
    status = out.status;
    if (phase == Phase::kFailed) {
      EXPECT_EQ(out.command.v_mps, 0.0);
      break;
    }
  }
  ASSERT_EQ(phase, Phase::kFailed);
  EXPECT_NE(status.find("no progress"), std::string::npos);
  EXPECT_EQ(m.blacklist().size(), 2u);
  EXPECT_EQ(m.goal_outcomes().no_progress, 2);
  EXPECT_EQ(m.goal_outcomes().overdue, 0);
}

// A goal given up is tried once more before the mission ends: here the wheels
// are stuck, so the only goal is given up twice and the mission ends
// DONE_WITH_UNREACHABLE, saying so; one try more, not a loop.
TEST(Mission, AGoalGivenUpIsTriedOnceMoreBeforeTheMissionEnds) {
  Mission m(test_options());
  int goals_taken = 0;
  Phase phase = Phase::kIdle, previous = Phase::kIdle;
  std::string status;
  bool retry_said = false;
  for (std::int64_t t = 0; t <= 60 * kSecond; t += 100'000) {
    m.on_pose(Pose2{5, 1.5, 0}, t);
    if (t % kSecond == 0) m.on_map(corridor(false, true), t);
    const auto out = step_with_inline_planning(m, t);
    phase = out.phase;
    status = out.status;
    retry_said = retry_said || status.find("once more") != std::string::npos;
    if (phase == Phase::kMoving && previous != Phase::kMoving) ++goals_taken;
    previous = phase;
    if (is_finished(phase)) break;
  }
  ASSERT_EQ(phase, Phase::kDoneWithUnreachable) << status;
  EXPECT_NE(status.find("1 given up"), std::string::npos) << status;
  EXPECT_TRUE(retry_said);
  EXPECT_EQ(goals_taken, 2);
}

// The goals given up are tried once more before the mission ends. Given up
// again while the robot drives (here it paces across the room, so no path
// gets shorter), they end it DONE_WITH_UNREACHABLE: a goal it could not get
// to is no robot failing, whatever max_consecutive_failures says. A robot
// that stands (stuck) in that round still fails.
enum class Motion { kPaces, kStands, kStandsWhileSlamJumps };
Phase retry_round_end(Motion motion, std::string* status, GoalOutcomes* outcomes) {
  MissionOptions o = test_options();
  o.max_consecutive_failures = 3;  // the first round gives up two goals, the second two more
  Mission m(o);
  const auto room = [] {
    return mapping::TypedMultiPolygon{
        typed_polygon(rectangle(0, 0, 20, 10, {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier}))};
  };
  Phase phase = Phase::kIdle;
  for (std::int64_t t = 0; t <= 400 * kSecond; t += 100'000) {
    // Pacing: up and down 2 m about the middle, never nearer either end.
    // Jumps: 3 m across every 2 s, the robot standing.
    double y = 5.0;
    if (motion == Motion::kPaces) y += 2.0 * std::sin(static_cast<double>(t) * 1e-6);
    if (motion == Motion::kStandsWhileSlamJumps && (t / (2 * kSecond)) % 2 == 1) y += 3.0;
    m.on_pose(Pose2{10, y, std::numbers::pi / 2}, t);
    if (t % kSecond == 0) m.on_map(room(), t);
    const auto out = step_with_inline_planning(m, t);
    phase = out.phase;
    *status = out.status;
    if (is_finished(phase)) break;
  }
  *outcomes = m.goal_outcomes();
  return phase;
}

TEST(Mission, GoalsGivenUpAgainInTheRetryRoundEndItUnreachableNotFailed) {
  std::string status;
  GoalOutcomes outcomes;
  ASSERT_EQ(retry_round_end(Motion::kPaces, &status, &outcomes), Phase::kDoneWithUnreachable) << status;
  EXPECT_NE(status.find("2 given up"), std::string::npos) << status;
  EXPECT_EQ(outcomes.no_progress + outcomes.overdue, 4);  // each end twice
}

TEST(Mission, AStuckRobotStillFailsInTheRetryRound) {
  std::string status;
  GoalOutcomes outcomes;
  for (const Motion motion : {Motion::kStands, Motion::kStandsWhileSlamJumps}) {  // a jump is no move
    ASSERT_EQ(retry_round_end(motion, &status, &outcomes), Phase::kFailed) << status;
    EXPECT_NE(status.find("3 goals in a row"), std::string::npos) << status;
    EXPECT_EQ(outcomes.no_progress + outcomes.overdue, 3);
  }
}

// No driving blind: with scan_timeout_us set, the robot stands until the
// first scan, stops when scans stop (map and pose still fresh), and goes on
// to the same goal when they come back.
TEST(Mission, NoLaserScansStopTheRobotUntilTheyComeBack) {
  MissionOptions o = test_options();
  o.scan_timeout_us = 500'000;
  Mission m(o);
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{5, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  EXPECT_TRUE(out.degraded);
  EXPECT_EQ(out.degraded_reason, "no laser scans");
  EXPECT_EQ(out.command.v_mps, 0.0);
  std::optional<Point> goal;
  std::int64_t t = 0;
  for (; t <= 2 * kSecond; t += 100'000) {  // scans, pose and map fresh: it drives
    m.on_scan(t);
    m.on_pose(Pose2{5 + 0.1 * static_cast<double>(t) / kSecond, 1.5, 0}, t);
    out = step_with_inline_planning(m, t);
    if (out.goal) goal = out.goal;
  }
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_FALSE(out.degraded);
  EXPECT_GT(out.command.v_mps, 0.0);
  // The laser goes silent; poses and maps keep coming.
  const std::int64_t last_scan = t - 100'000;
  for (; t <= last_scan + 1'000'000; t += 100'000) {
    m.on_pose(Pose2{5.2, 1.5, 0}, t);
    if (t % kSecond == 0) m.on_map(corridor(false, true), t);
    out = step_with_inline_planning(m, t);
    if (t - last_scan > 500'000) {
      EXPECT_TRUE(out.degraded) << t;
      EXPECT_EQ(out.command.v_mps, 0.0) << t;
      EXPECT_NE(out.status.find("no laser scan for"), std::string::npos) << out.status;
    }
  }
  EXPECT_EQ(out.phase, Phase::kMoving);  // the goal is kept
  m.on_scan(t);
  m.on_pose(Pose2{5.2, 1.5, 0}, t);
  out = step_with_inline_planning(m, t);
  EXPECT_FALSE(out.degraded);
  EXPECT_GT(out.command.v_mps, 0.0);
  ASSERT_TRUE(goal && out.goal);
  EXPECT_LT(distance(*goal, *out.goal), 0.5);
}

// The robot on its way down the corridor to its open right end is held
// still by the scan guard from 4 s on (a pane the map did not hold), and
// the maps from then on hold what held it: a block across the corridor's
// middle, the way round it longer than the way the robot had.
mapping::TypedMultiPolygon corridor_with_a_block(bool block) {
  const auto outer = rectangle(0, 0, 20, 3, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle});
  if (!block) return {typed_polygon(outer)};
  return {typed_polygon(outer, {rectangle_hole(11.0, 0.9, 11.4, 2.1)})};
}

// When the held mission gives its goal up (s; -1: not within 30 s), the
// guard block told at 4 s or not.
double held_goal_given_up_at_s(bool tell_the_block) {
  Mission m(test_options());  // progress timeout 5 s
  for (std::int64_t t = 0; t <= 30 * kSecond; t += 100'000) {
    if (t % kSecond == 0) m.on_map(corridor_with_a_block(t >= 5 * kSecond), t);
    m.on_pose(Pose2{10, 1.5, 0}, t);  // held: it never moves
    if (t == 4 * kSecond && tell_the_block) {
      EXPECT_TRUE(m.on_guard_block(t));
    }
    step_with_inline_planning(m, t);
    if (m.goal_outcomes().given_up() > 0) {
      EXPECT_EQ(m.goal_outcomes().no_progress, 1);
      return static_cast<double>(t) * 1e-6;
    }
  }
  return -1.0;
}

TEST(Mission, AGuardBlockStartsTheGoalsProgressAnewFromThePlansOnTheNextMaps) {
  // Untold, the goal is given up at its progress timeout from the start.
  EXPECT_NEAR(held_goal_given_up_at_s(false), 5.1, 0.05);
  // Told, the time starts anew at the block, and again on the plans of the
  // next two maps (5 s and 6 s, the longer way round the baseline): given
  // up 5 s after the second, if the robot still does not move.
  EXPECT_NEAR(held_goal_given_up_at_s(true), 11.1, 0.05);
}

TEST(Mission, GuardBlocksAreBoundedPerGoalAndOnlyWhileMoving) {
  MissionOptions o = test_options();
  o.max_guard_blocks_per_goal = 2;
  Mission m(o);
  EXPECT_FALSE(m.on_guard_block(0));  // no mission yet
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_TRUE(m.on_guard_block(100'000));
  out = m.step(200'000);
  EXPECT_NE(out.status.find("held by the scan guard (1 of 2"), std::string::npos) << out.status;
  EXPECT_TRUE(out.plan_request.has_value());  // replanned at once, not at the period
  EXPECT_TRUE(m.on_guard_block(300'000));
  EXPECT_FALSE(m.on_guard_block(400'000));  // this goal's holds are used up
  MissionOptions off = test_options();
  off.max_guard_blocks_per_goal = 0;
  Mission n(off);
  n.on_map(corridor(false, true), 0);
  n.on_pose(Pose2{10, 1.5, 0}, 0);
  ASSERT_EQ(step_with_inline_planning(n, 0).phase, Phase::kMoving);
  EXPECT_FALSE(n.on_guard_block(100'000));
}

TEST(Mission, AGoalThatMovesOnWithItsFrontierIsProgress) {
  // The corridor's far end recedes 0.5 m a second (the robot sees further
  // down it) while the path to it does not get shorter: no give-up.
  Mission m(test_options());
  auto receding = [](double length_m) {
    return mapping::TypedMultiPolygon{typed_polygon(
        rectangle(0, 0, length_m, 3, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))};
  };
  for (std::int64_t t = 0; t <= 30 * kSecond; t += 100'000) {
    if (t % kSecond == 0) m.on_map(receding(20.0 + 0.5 * static_cast<double>(t / kSecond)), t);
    m.on_pose(Pose2{15, 1.5, 0}, t);
    const auto out = step_with_inline_planning(m, t);
    ASSERT_EQ(out.phase, Phase::kMoving) << "at " << t << ": " << out.status;
  }
  EXPECT_TRUE(m.blacklist().empty());
}

TEST(Mission, AGoalThatMovesOnForEverIsGivenUpAtItsDeadline) {
  // The same receding frontier, but the robot never gets anywhere: progress
  // by the frontier alone does not keep a goal for ever.
  Mission m(test_options());
  auto receding = [](double length_m) {
    return mapping::TypedMultiPolygon{typed_polygon(
        rectangle(0, 0, length_m, 3, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))};
  };
  std::int64_t given_up_at = -1;
  for (std::int64_t t = 0; t <= 200 * kSecond && given_up_at < 0; t += 100'000) {
    if (t % kSecond == 0) m.on_map(receding(20.0 + 0.5 * static_cast<double>(t / kSecond)), t);
    m.on_pose(Pose2{15, 1.5, 0}, t);
    step_with_inline_planning(m, t);
    if (m.goal_outcomes().given_up() > 0) given_up_at = t;
  }
  // Deadline: progress timeout (5 s) + 4 x the first path (4.65 m) at 0.4 m/s = 51.5 s.
  ASSERT_GT(given_up_at, 0);
  EXPECT_NEAR(static_cast<double>(given_up_at) * 1e-6, 51.5, 0.5);
  // Counted as overdue: it progressed all along.
  EXPECT_EQ(m.goal_outcomes().overdue, 1);
  EXPECT_EQ(m.goal_outcomes().no_progress, 0);
  EXPECT_EQ(m.blacklist().size(), 1u);
}

TEST(Mission, StaleInputsStopTheRobotUntilTheyAreFresh) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{5, 1.5, 0}, 0);
  step_with_inline_planning(m, 0);
  m.on_pose(Pose2{5, 1.5, 0}, 200'000);
  auto out = step_with_inline_planning(m, 200'000);
  ASSERT_EQ(out.phase, Phase::kMoving);
  ASSERT_GT(out.command.v_mps, 0.0);
  out = step_with_inline_planning(m, 1'500'000);  // the last pose is 1.3 s old
  EXPECT_TRUE(out.degraded);
  EXPECT_EQ(out.phase, Phase::kMoving);
  EXPECT_EQ(out.command.v_mps, 0.0);
  EXPECT_EQ(out.command.omega_radps, 0.0);
  EXPECT_NE(out.status.find("pose is stale"), std::string::npos);
  m.on_pose(Pose2{5, 1.5, 0}, 1'550'000);
  out = step_with_inline_planning(m, 1'600'000);
  EXPECT_FALSE(out.degraded);
  EXPECT_EQ(out.phase, Phase::kMoving);
}

// Two rooms joined by a 0.66 m gap: passable for a 0.3 m robot, not with a
// 0.05 m clearance margin on top. The frontier is in the right room.
mapping::TypedMultiPolygon rooms_with_a_narrow_gap() {
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(5, 0), Point(5, 2.17), Point(5.2, 2.17), Point(5.2, 0), Point(10, 0), Point(10, 5),
       Point(5.2, 5), Point(5.2, 2.83), Point(5, 2.83), Point(5, 5), Point(0, 5)},
      {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle,
       E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle}})};
}

TEST(Mission, SqueezesThroughANarrowGapWithoutTheMargin) {
  MissionOptions o = test_options();
  o.planner.cspace.clearance_margin_m = 0.05;
  o.planner.approach_range_m = 0.0;  // the fallback alone (an approach point would look through the gap first)
  Mission m(o);
  m.on_map(rooms_with_a_narrow_gap(), 0);
  m.on_pose(Pose2{2, 2.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_NE(out.status.find("without clearance margin"), std::string::npos) << out.status;
  EXPECT_GT(out.goal->x(), 9.0);

  o.tight_fallback = false;
  Mission strict(o);
  strict.on_map(rooms_with_a_narrow_gap(), 0);
  strict.on_pose(Pose2{2, 2.5, 0}, 0);
  EXPECT_EQ(step_with_inline_planning(strict, 0).phase, Phase::kSelecting);
  strict.on_map(rooms_with_a_narrow_gap(), 1'000'000);
  strict.on_pose(Pose2{2, 2.5, 0}, 1'000'000);
  out = step_with_inline_planning(strict, 1'000'000);
  // Before it says so, one turn on the spot (MissionOptions::look_around).
  EXPECT_EQ(out.phase, Phase::kSelecting);
  EXPECT_NE(out.status.find("looking around"), std::string::npos) << out.status;
  double theta = 0.0, turned = 0.0;
  for (std::int64_t t = 1'100'000; t <= 12'000'000 && !is_finished(out.phase); t += 100'000) {
    if (t % 1'000'000 == 0) strict.on_map(rooms_with_a_narrow_gap(), t);
    strict.on_pose(Pose2{2, 2.5, theta}, t);
    out = step_with_inline_planning(strict, t);
    EXPECT_EQ(out.command.v_mps, 0.0);  // on the spot
    EXPECT_GE(out.command.omega_radps, 0.0);
    theta = geometry::wrap_angle(theta + out.command.omega_radps * 0.1);
    turned += out.command.omega_radps * 0.1;
  }
  EXPECT_GE(turned, 2.0 * std::numbers::pi);  // once round, then done
  EXPECT_LT(turned, 2.0 * std::numbers::pi + 1.0);
  EXPECT_EQ(out.looks_around, 1);
  // Done, but truthfully: a frontier is left that the robot cannot reach.
  EXPECT_EQ(out.phase, Phase::kDoneWithUnreachable);
  ASSERT_FALSE(out.frontiers.empty());
  for (const auto& f : out.frontiers) EXPECT_NE(f.reason, FrontierReason::kReachable);
  EXPECT_NE(out.status.find("none reachable"), std::string::npos) << out.status;
}

// Two rooms as rooms_with_a_narrow_gap(), the gap `gap_m` wide, and a
// second frontier: room A's west wall.
mapping::TypedMultiPolygon rooms_with_a_narrow_gap_and_a_west_frontier(double gap_m) {
  const double y0 = 2.5 - gap_m / 2, y1 = 2.5 + gap_m / 2;
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(5, 0), Point(5, y0), Point(5.2, y0), Point(5.2, 0), Point(10, 0), Point(10, 5),
       Point(5.2, 5), Point(5.2, y1), Point(5, y1), Point(5, 5), Point(0, 5)},
      {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle,
       E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier}})};
}

// Room B's frontier is seen through the gap from an approach point in room
// A; its own place is beyond a gap the margin closes. Once the approach point
// is reached and the frontier is still there, the robot goes through the gap
// without the margin, although room A's west frontier is reachable with it
// (b41: a floor's whole open plan lay behind such a gap), with part of the
// margin kept (way_in_margin_m). Where the gap is too narrow for that, it
// goes on to the west frontier.
TEST(Mission, ReachedApproachPointLeadsInThroughAGapTheFullMarginCloses) {
  MissionOptions o = test_options();
  // With the 0.3 m radius a gap needs 0.7 m with the margin, 0.65 m for a way in, 0.6 m without.
  o.planner.cspace.clearance_margin_m = 0.05;
  o.way_in_margin_m = 0.025;
  for (const double gap_m : {0.66, 0.62, 0.56}) {
    SCOPED_TRACE(gap_m);
    const auto map = rooms_with_a_narrow_gap_and_a_west_frontier(gap_m);
    Mission m(o);
    m.on_map(map, 0);
    m.on_pose(Pose2{4, 2.5, 0}, 0);
    auto out = step_with_inline_planning(m, 0);
    ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
    ASSERT_TRUE(out.goal.has_value());
    const Point approach = *out.goal;
    EXPECT_LT(approach.x(), 5.0);  // in room A: the approach point, with the margin
    EXPECT_GT(approach.x(), 3.0);
    EXPECT_EQ(out.status.find("without clearance margin"), std::string::npos) << out.status;
    m.on_pose(Pose2{approach.x(), approach.y(), 0}, 200'000);  // there, facing room B
    out = step_with_inline_planning(m, 200'000);
    ASSERT_EQ(out.phase, Phase::kSelecting) << out.status;
    ASSERT_NE(out.status.find("reached"), std::string::npos) << out.status;
    // A newer map: room B's frontier is still there.
    m.on_map(map, 1'000'000);
    m.on_pose(Pose2{approach.x(), approach.y(), 0}, 1'000'000);
    out = step_with_inline_planning(m, 1'000'000);
    ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
    ASSERT_TRUE(out.goal.has_value());
    if (gap_m > 0.65) {
      EXPECT_GT(out.goal->x(), 5.2) << out.status;  // through the gap
      EXPECT_NE(out.status.find("clearance margin 0.025 m: the frontier seen from its approach point"),
                std::string::npos)
          << out.status;
      EXPECT_EQ(out.ways_in, 1);
      // It is followed without the margin too, through the gap.
      m.on_pose(Pose2{approach.x() + 0.1, approach.y(), 0}, 1'100'000);
      out = step_with_inline_planning(m, 1'100'000);
      m.on_pose(Pose2{approach.x() + 0.2, approach.y(), 0}, 2'000'000);
      out = step_with_inline_planning(m, 2'000'000);
      EXPECT_EQ(out.phase, Phase::kMoving) << out.status;
      EXPECT_GT(out.goal->x(), 5.2) << out.status;
    } else {
      EXPECT_LT(out.goal->x(), 1.0) << out.status;  // room A's west frontier, with the margin
      EXPECT_EQ(out.status.find("without clearance margin"), std::string::npos) << out.status;
      EXPECT_EQ(out.ways_in, 0);
    }
  }
}

// A robot that stands where the margin leaves no room (here 0.32 m from a
// wall: inside the robot's radius plus margin, outside its radius) plans its
// next goal without the margin instead of failing.
TEST(Mission, ARobotOutsideTheMarginsCSpacePlansWithoutTheMargin) {
  MissionOptions o = test_options();
  o.planner.cspace.clearance_margin_m = 0.05;
  o.planner.start_snap_distance_m = 0.02;
  Mission m(o);
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{5, 0.32, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_NE(out.status.find("without clearance margin"), std::string::npos) << out.status;

  o.tight_fallback = false;
  Mission strict(o);
  strict.on_map(corridor(false, true), 0);
  strict.on_pose(Pose2{5, 0.32, 0}, 0);
  out = step_with_inline_planning(strict, 0);
  EXPECT_EQ(out.phase, Phase::kSelecting);
  EXPECT_NE(out.status.find("not within"), std::string::npos) << out.status;
}

// The mission's output once two maps in a row (one second apart) showed
// `map` with the robot at `pose`: what DONE needs (done_confirmations).
MissionOutput after_two_maps(Mission& m, const mapping::TypedMultiPolygon& map, const Pose2& pose) {
  for (std::int64_t t : {0 * kSecond, 1 * kSecond}) {
    m.on_map(map, t);
    m.on_pose(pose, t);
    (void)step_with_inline_planning(m, t);
  }
  return step_with_inline_planning(m, kSecond + 1);
}

// A closed corridor and, behind its top wall, a sliver of free space whose
// far side is frontier (a misaligned scan beyond a thin wall): no reachable
// place has it in view, so driving cannot show more. DONE, with it listed.
TEST(Mission, DoneWhenTheOnlyFrontierLeftIsBehindAWall) {
  const mapping::TypedMultiPolygon map = {
      typed_polygon(rectangle(0, 0, 20, 3)),
      typed_polygon(rectangle(5, 3.05, 9, 3.15, {E::kObstacle, E::kFrontier, E::kFrontier, E::kFrontier}))};
  Mission m(test_options());
  const auto out = after_two_maps(m, map, Pose2{2, 1.5, 0});
  EXPECT_EQ(out.phase, Phase::kDone) << out.status;
  ASSERT_EQ(out.frontiers.size(), 1u);
  EXPECT_EQ(out.frontiers[0].reason, FrontierReason::kOutOfView);
  EXPECT_NE(out.status.find("1 behind walls"), std::string::npos) << out.status;
}

TEST(Mission, DoneWhenTheOnlyFrontierLeftIsAPocket) {
  // A room whose only frontier is the shadow in a 0.2 m slot of its top wall
  // (the gap between two desks): no robot reaches past it, so the room is
  // explored, and the slot's frontier is listed as a pocket.
  const mapping::TypedMultiPolygon map = {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(6, 0), Point(6, 4), Point(3.2, 4), Point(3.2, 4.8), Point(3.15, 4.8), Point(3, 4),
       Point(0, 4)},
      {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle,
       E::kObstacle}})};
  for (const double reach_m : {0.02, 0.0}) {
    MissionOptions o = test_options();
    o.planner.reach_past_frontier_m = reach_m;
    Mission m(o);
    const auto out = after_two_maps(m, map, Pose2{1, 2, 0});
    if (reach_m == 0.0) {  // the test off: the slot is a goal
      EXPECT_EQ(out.phase, Phase::kMoving) << out.status;
      continue;
    }
    EXPECT_EQ(out.phase, Phase::kDone) << out.status;
    ASSERT_EQ(out.frontiers.size(), 1u);
    EXPECT_EQ(out.frontiers[0].reason, FrontierReason::kPocket);
    EXPECT_NE(out.status.find("1 in pockets narrower than the robot"), std::string::npos) << out.status;
  }
}

TEST(Mission, DoneWhenTheOnlyFrontierLeftIsEnclosed) {
  // A room explored but for the unseen right side of a 2 x 1 m desk: with
  // min_enclosed_area_m2 above the desk's area that frontier is no goal, and
  // the room is explored, the frontier listed as enclosed.
  auto desk = testing::rectangle_hole(4, 1.5, 6, 2.5);
  desk.types = {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle};
  const mapping::TypedMultiPolygon map = {typed_polygon(rectangle(0, 0, 10, 4), {desk})};
  for (const double min_m2 : {3.0, 0.0}) {
    MissionOptions o = test_options();
    o.planner.min_enclosed_area_m2 = min_m2;
    Mission m(o);
    const auto out = after_two_maps(m, map, Pose2{1, 1, 0});
    if (min_m2 == 0.0) {  // off: the desk's side is a goal
      EXPECT_EQ(out.phase, Phase::kMoving) << out.status;
      continue;
    }
    EXPECT_EQ(out.phase, Phase::kDone) << out.status;
    ASSERT_EQ(out.frontiers.size(), 1u);
    EXPECT_EQ(out.frontiers[0].reason, FrontierReason::kEnclosed);
    EXPECT_NE(out.status.find("1 enclosed in small unknown regions"), std::string::npos) << out.status;
  }
}

// A hall explored, and through a 0.3 m gap (the robot is 0.6 m across) a
// room whose far wall is frontier: the margin's plan has no path to
// it, the plan without the margin neither, even for a disk 0.1 m narrower:
// behind a gap narrower than the robot, so DONE with it listed. Through a
// 0.56 m gap (within the tolerance of the robot's width: the map may have
// narrowed a door it fits) the robot goes to look at the gap from its
// mouth: not DONE.
TEST(Mission, DoneWhenTheOnlyFrontiersLeftAreBehindAGapNarrowerThanTheRobot) {
  for (const double gap_m : {0.3, 0.56}) {
    MissionOptions o = test_options();  // robot radius 0.3 m, margin 0.05 m
    o.planner.narrow_gap_tolerance_m = 0.05;
    Mission m(o);
    const auto out = after_two_maps(
        m, testing::a_room_behind_a_gap(gap_m, -10.0, E::kObstacle, E::kFrontier), Pose2{2, 2, 0});
    ASSERT_FALSE(out.frontiers.empty()) << out.status;
    if (gap_m > 0.5) {
      EXPECT_EQ(out.phase, Phase::kMoving) << out.status;
      ASSERT_TRUE(out.goal.has_value());
      EXPECT_GT(out.goal->x(), 9.0);  // the gap runs x = 10..11
      EXPECT_LT(out.goal->x(), 10.0);
      continue;
    }
    EXPECT_EQ(out.phase, Phase::kDone) << out.status;
    for (const auto& f : out.frontiers) EXPECT_EQ(f.reason, FrontierReason::kBehindNarrowGap);
    EXPECT_NE(out.status.find(std::to_string(out.frontiers.size()) + " behind gaps narrower than the robot"),
              std::string::npos)
        << out.status;
  }
}

// A frontier at the end of a slot in a room behind a 0.3 m gap, seen from
// the room's C-space only, 2 m from it: DONE, the frontier behind the gap.
// (It was "too narrow", which ended the mission DONE_WITH_UNREACHABLE.)
TEST(Mission, DoneWhenAFrontierSeenOnlyFromARoomBehindANarrowGapIsLeft) {
  MissionOptions o = test_options();  // robot radius 0.3 m, margin 0.05 m
  o.planner.narrow_gap_tolerance_m = 0.05;
  Mission m(o);
  const auto out = after_two_maps(m, testing::a_slot_in_a_room_behind_a_gap(0.3), Pose2{2, 2, 0});
  EXPECT_EQ(out.phase, Phase::kDone) << out.status;
  ASSERT_EQ(out.frontiers.size(), 1u) << out.status;
  EXPECT_EQ(out.frontiers[0].reason, FrontierReason::kBehindNarrowGap);
  EXPECT_NEAR(out.frontiers[0].position.y(), 6.0, 1e-6);
}

// A door 0.66 m wide in the world that the map narrowed to 0.56 m (the robot
// needs 0.6 m without the margin): its room's frontier has no path, but a
// disk 0.05 m smaller gets through, so the robot drives to the door's mouth
// and faces the room. What the laser sees there decides: its live view
// (PlanRequest::live_view, the door as wide as it is) opens the door and the
// next plan goes through, without the margin; with no such view the door
// stays shut, the mouth is not offered again, and the mission ends
// DONE_WITH_UNREACHABLE with the room's frontiers without a path (the robot
// looked; whether its body would pass is not settled).
TEST(Mission, ADoorTheMapNarrowedIsLookedAtFromItsMouthAndGoneThroughIfTheRobotFits) {
  const auto map = testing::a_room_behind_a_gap(0.56, -10.0, E::kObstacle, E::kFrontier);
  // The scan at the mouth: the free space through the door as it is (y = 1.67..2.33).
  const auto door_seen = std::make_shared<const mapping::TypedMultiPolygon>(
      mapping::TypedMultiPolygon{typed_polygon(rectangle(9.0, 1.67, 12.0, 2.33))});
  for (const bool laser_sees_through : {true, false}) {
    SCOPED_TRACE(laser_sees_through);
    MissionOptions o = test_options();  // robot radius 0.3 m, margin 0.05 m
    o.planner.cspace.clearance_margin_m = 0.05;
    o.planner.narrow_gap_tolerance_m = 0.05;
    Mission m(o);
    bool at_the_mouth = false;
    auto planner = [&](PlanRequest request) {
      if (at_the_mouth && laser_sees_through) request.live_view = door_seen;
      return compute_plan(request);
    };
    m.on_map(map, 0);
    m.on_pose(Pose2{2, 2, 0}, 0);
    auto out = step_with_inline_planning(m, 0, planner);
    ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
    ASSERT_TRUE(out.goal.has_value());
    const Point mouth = *out.goal;
    EXPECT_GT(mouth.x(), 9.0);
    EXPECT_LT(mouth.x(), 10.0);
    EXPECT_NE(out.status.find("without clearance margin"), std::string::npos) << out.status;
    // There, facing the room: reached.
    at_the_mouth = true;
    m.on_pose(Pose2{mouth.x(), mouth.y(), 0}, kSecond / 2);
    out = step_with_inline_planning(m, kSecond / 2, planner);
    ASSERT_EQ(out.phase, Phase::kSelecting) << out.status;
    ASSERT_NE(out.status.find("reached"), std::string::npos) << out.status;
    MissionOutput last;
    for (std::int64_t t = kSecond; t <= 40 * kSecond && last.phase != Phase::kDone &&
                            last.phase != Phase::kDoneWithUnreachable && !last.goal;
         t += kSecond / 2) {
      if (t % kSecond == 0) m.on_map(map, t);
      m.on_pose(Pose2{mouth.x(), mouth.y(), 0}, t);
      last = step_with_inline_planning(m, t, planner);
    }
    if (laser_sees_through) {
      ASSERT_EQ(last.phase, Phase::kMoving) << last.status;
      ASSERT_TRUE(last.goal.has_value());
      EXPECT_GT(last.goal->x(), 11.0) << "in the room, through the door";
      EXPECT_NE(last.status.find("without clearance margin"), std::string::npos) << last.status;
    } else {
      ASSERT_EQ(last.phase, Phase::kDoneWithUnreachable) << last.status;
      ASSERT_FALSE(last.frontiers.empty());
      for (const auto& f : last.frontiers) EXPECT_EQ(f.reason, FrontierReason::kNoPath);
      EXPECT_EQ(last.goals.reached, 1);
    }
  }
}

TEST(Mission, CountsDistanceTravelledButNotPoseJumps) {
  Mission m(test_options());
  m.on_pose(Pose2{0, 0, 0}, 0);
  m.on_pose(Pose2{0.3, 0.4, 0}, 1);
  m.on_pose(Pose2{10, 0.4, 0}, 2);  // a SLAM jump
  m.on_pose(Pose2{10, 0.9, 0}, 3);
  m.on_pose(Pose2{std::nan(""), 0, 0}, 4);  // ignored
  EXPECT_NEAR(step_with_inline_planning(m, 5).distance_travelled_m, 1.0, 1e-12);
}

TEST(Mission, KeepsItsGoalWhenAnotherBecomesCheaper) {
  // Heading for the right end; then a new frontier opens right behind the
  // robot. Greedy would turn round; a committed mission keeps its goal.
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{12, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving);
  const Point goal = *out.goal;
  m.on_map(corridor(true, true), 900'000);
  m.on_pose(Pose2{12.5, 1.5, 0}, 1'000'000);
  m.on_map({typed_polygon(rectangle(0, 0, 20, 3, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle})),
            typed_polygon(rectangle(10, 3, 11.5, 6, {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle}))},
           1'000'000);
  out = step_with_inline_planning(m, 1'000'000);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_NEAR(out.goal->x(), goal.x(), 0.1);
  EXPECT_EQ(m.goal_outcomes().seen + m.goal_outcomes().given_up(), 0);
}

TEST(Mission, WaitsForStartWhenNotAutostarting) {
  MissionOptions o = test_options();
  o.autostart = false;
  Mission m(o);
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  auto out = step_with_inline_planning(m, 0);
  EXPECT_EQ(out.phase, Phase::kWaitingStart);
  EXPECT_EQ(out.command.v_mps, 0.0);
  EXPECT_FALSE(out.plan_request.has_value());
  EXPECT_EQ(m.on_command(MissionCommand::kResume, 100'000), "not started: send start");
  EXPECT_EQ(m.on_command(MissionCommand::kStart, 100'000), "");
  m.on_pose(Pose2{10, 1.5, 0}, 200'000);
  out = step_with_inline_planning(m, 200'000);
  EXPECT_EQ(out.phase, Phase::kMoving) << out.status;
}

TEST(Mission, PauseStopsTheWheelsAndResumeGoesOnToTheSameGoal) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  step_with_inline_planning(m, 0);
  m.on_pose(Pose2{10, 1.5, 0}, 100'000);
  auto out = step_with_inline_planning(m, 100'000);
  ASSERT_GT(out.command.v_mps, 0.0);
  const Point goal = *out.goal;
  EXPECT_EQ(m.on_command(MissionCommand::kPause, 150'000), "");
  EXPECT_EQ(m.on_command(MissionCommand::kPause, 160'000), "");  // idempotent
  // Paused far longer than the progress timeout: no goal is given up.
  for (std::int64_t t = 200'000; t <= 30 * kSecond; t += 100'000) {
    m.on_pose(Pose2{10, 1.5, 0}, t);
    if (t % kSecond == 0) m.on_map(corridor(false, true), t);
    out = step_with_inline_planning(m, t);
    ASSERT_EQ(out.phase, Phase::kPaused);
    ASSERT_EQ(out.command.v_mps, 0.0);
    ASSERT_EQ(out.command.omega_radps, 0.0);
  }
  EXPECT_EQ(m.on_command(MissionCommand::kResume, 30 * kSecond + 50'000), "");
  m.on_pose(Pose2{10, 1.5, 0}, 30 * kSecond + 100'000);
  out = step_with_inline_planning(m, 30 * kSecond + 100'000);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_NEAR(out.goal->x(), goal.x(), 1e-9);
  EXPECT_GT(out.command.v_mps, 0.0);
  EXPECT_TRUE(m.blacklist().empty());
}

TEST(Mission, HomeDrivesBackToTheStartPoseAndStopsThere) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{5, 1.5, 0}, 0);
  step_with_inline_planning(m, 0);
  // The robot got to x = 15; then: home.
  m.on_pose(Pose2{15, 1.5, 0}, 5 * kSecond);
  m.on_map(corridor(false, true), 5 * kSecond);
  step_with_inline_planning(m, 5 * kSecond);
  EXPECT_EQ(m.on_command(MissionCommand::kHome, 5 * kSecond + 10'000), "");
  m.on_pose(Pose2{15, 1.5, 0}, 5 * kSecond + 100'000);
  auto out = step_with_inline_planning(m, 5 * kSecond + 100'000);
  ASSERT_EQ(out.phase, Phase::kHoming) << out.status;
  ASSERT_TRUE(out.goal.has_value());
  EXPECT_NEAR(out.goal->x(), 5.0, 1e-6);
  EXPECT_NEAR(out.goal->y(), 1.5, 1e-6);
  ASSERT_GE(out.path.size(), 2u);
  m.on_pose(Pose2{15, 1.5, std::numbers::pi}, 5 * kSecond + 200'000);
  out = step_with_inline_planning(m, 5 * kSecond + 200'000);
  EXPECT_GT(out.command.v_mps, 0.0);  // heading home (west)
  m.on_pose(Pose2{5.1, 1.5, std::numbers::pi}, 30 * kSecond);
  m.on_map(corridor(false, true), 30 * kSecond);
  out = step_with_inline_planning(m, 30 * kSecond);
  EXPECT_EQ(out.phase, Phase::kHome) << out.status;
  EXPECT_EQ(out.command.v_mps, 0.0);
  // Home is a stop: a newer map changes nothing until a new start.
  m.on_map(corridor(true, true), 31 * kSecond);
  m.on_pose(Pose2{5.1, 1.5, 0}, 31 * kSecond);
  EXPECT_EQ(step_with_inline_planning(m, 31 * kSecond).phase, Phase::kHome);
  EXPECT_EQ(m.on_command(MissionCommand::kStart, 31 * kSecond + 10'000), "");
  m.on_pose(Pose2{5.1, 1.5, 0}, 31 * kSecond + 100'000);
  EXPECT_EQ(step_with_inline_planning(m, 31 * kSecond + 100'000).phase, Phase::kMoving);
}

// The robot started in room A and drove through the door into room B; the
// newest map has the door shut (a slit narrower than the robot). With the
// margin there is no way home; without it and along the way the robot drove
// (the trail the explorer adds to tight requests) there is.
TEST(Mission, HomeGoesBackAlongTheWayTheRobotCameThroughAGapTheMapShut) {
  const std::vector<Point> drove{{8, 2}, {10.5, 2}, {13, 2}};
  auto home_after_a_while = [&](bool with_trail) {
    Mission m(test_options());
    auto planner = [&](PlanRequest request) {
      if (with_trail && request.tight) request.trail = std::make_shared<const std::vector<Point>>(drove);
      return compute_plan(request);
    };
    m.on_map(testing::a_room_cut_off_behind_a_slit(), 0);
    m.on_pose(Pose2{8, 2, 0}, 0);
    step_with_inline_planning(m, 0, planner);  // the start pose: (8, 2)
    EXPECT_EQ(m.on_command(MissionCommand::kHome, 10'000), "");
    MissionOutput out;
    int steps_with_goal = 0;  // a few: the speed ramps up from 0
    for (std::int64_t t = 100'000; t <= 5 * kSecond && steps_with_goal < 3; t += 100'000) {
      m.on_pose(Pose2{13, 2, std::numbers::pi}, t);
      if (t % kSecond == 0) m.on_map(testing::a_room_cut_off_behind_a_slit(), t);
      out = step_with_inline_planning(m, t, planner);
      if (out.phase != Phase::kHoming) break;
      if (out.goal) ++steps_with_goal;
    }
    return out;
  };
  const auto out = home_after_a_while(true);
  ASSERT_EQ(out.phase, Phase::kHoming) << out.status;
  ASSERT_TRUE(out.goal.has_value());
  EXPECT_NEAR(out.goal->x(), 8.0, 1e-6);
  ASSERT_GE(out.path.size(), 2u);
  for (const auto& p : out.path) EXPECT_NEAR(p.y(), 2.0, 0.06) << "along the trail, through the slit";
  EXPECT_GT(out.command.v_mps, 0.0);

  const auto without = home_after_a_while(false);
  EXPECT_EQ(without.phase, Phase::kFailed) << without.status;
  EXPECT_NE(without.status.find("cannot go home"), std::string::npos);
}

TEST(Mission, StopEndsTheMissionAndFreezesItsClock) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  step_with_inline_planning(m, 0);
  m.on_pose(Pose2{10, 1.5, 0}, 2 * kSecond);
  step_with_inline_planning(m, 2 * kSecond);
  EXPECT_EQ(m.on_command(MissionCommand::kStop, 2 * kSecond), "");
  m.on_pose(Pose2{10, 1.5, 0}, 9 * kSecond);
  const auto out = step_with_inline_planning(m, 9 * kSecond);
  EXPECT_EQ(out.phase, Phase::kStopped);
  EXPECT_EQ(out.command.v_mps, 0.0);
  EXPECT_NEAR(out.mission_time_s, 2.0, 1e-9);
}

// The corridor and, above it, a 3 x 3 m nook through a door at x 6..7: 1 m
// wide when open, 0.4 m when shut (its frame seen from inside). Not yet
// mapped, the nook's far side is frontier and the corridor closed; mapped,
// the nook is closed and the corridor's right end frontier.
mapping::TypedMultiPolygon corridor_with_a_nook(bool door_open, bool nook_mapped) {
  const double x0 = door_open ? 6.0 : 6.3, x1 = door_open ? 7.0 : 6.7;
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(20, 0), Point(20, 3), Point(x1, 3), Point(x1, 3.5), Point(8, 3.5), Point(8, 6.5),
       Point(5, 6.5), Point(5, 3.5), Point(x0, 3.5), Point(x0, 3), Point(0, 3)},
      {E::kObstacle, nook_mapped ? E::kFrontier : E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle,
       E::kObstacle, nook_mapped ? E::kObstacle : E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle,
       E::kObstacle, E::kObstacle}})};
}

// Into the nook (door open), to its goal; then the map shuts the door. The
// mission is left at the goal (in `at`), the new map in, at `t`.
void shut_in_the_nook(Mission& m, std::int64_t& t, Pose2& at) {
  m.on_map(corridor_with_a_nook(true, false), 0);
  m.on_pose(Pose2{6.5, 1.5, std::numbers::pi / 2}, 0);
  auto out = step_with_inline_planning(m, 0);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  ASSERT_GT(out.goal->y(), 5.0);
  const Point goal = *out.goal;
  for (t = 100'000; out.phase == Phase::kMoving && t < 10 * kSecond; t += 100'000) {
    const double y = std::min(goal.y(), 1.5 + 0.4 * static_cast<double>(t) * 1e-6 * 4);
    at = Pose2{goal.x(), y, std::numbers::pi / 2};
    m.on_pose(at, t);
    out = step_with_inline_planning(m, t);
  }
  ASSERT_EQ(out.phase, Phase::kSelecting) << out.status;
  m.on_map(corridor_with_a_nook(false, true), t);
}

bool mission_finished(const MissionOutput& o) { return is_finished(o.phase); }

// The robot standing at `at` in the shut nook, a newer map each second,
// until `until` holds of the output or `seconds` have passed.
template <class Until>
MissionOutput stand_in_the_shut_nook(Mission& m, std::int64_t& t, const Pose2& at, int seconds, Until&& until) {
  MissionOutput out;
  for (int k = 0; k < seconds && !until(out); ++k) {
    t += kSecond;
    m.on_map(corridor_with_a_nook(false, true), t);
    m.on_pose(at, t);
    out = step_with_inline_planning(m, t);
  }
  return out;
}

// Shut in the nook and standing there until the way back begins.
void start_backing_out_of_the_shut_nook(Mission& m, std::int64_t& t, Pose2& at, MissionOutput& out) {
  shut_in_the_nook(m, t, at);
  out = stand_in_the_shut_nook(m, t, at, 5, [](const MissionOutput& o) { return o.backs_out > 0; });
  ASSERT_EQ(out.backs_out, 1) << out.status;
}

TEST(Mission, BacksOutOfANookTheMapShutBeforeCallingTheRestUnreachable) {
  MissionOptions o = test_options();
  o.look_around = false;  // the way back alone
  Mission m(o);
  std::int64_t t = 0;
  Pose2 at;
  shut_in_the_nook(m, t, at);
  // No goal from the nook: after the confirmations it backs out, driving.
  auto backing_out = [](const MissionOutput& o) { return o.backs_out > 0 || is_finished(o.phase); };
  MissionOutput out = stand_in_the_shut_nook(m, t, at, 5, backing_out);
  ASSERT_EQ(out.backs_out, 1) << out.status;
  ASSERT_EQ(out.phase, Phase::kSelecting) << out.status;
  EXPECT_NE(out.status.find("backing out"), std::string::npos) << out.status;
  // Down the way it came (the robot put where the commands take it, roughly):
  // in the corridor the right end is a goal again.
  double fastest = 0.0;
  for (double y = at.y_m; y > 1.0 && out.phase != Phase::kMoving; y -= 0.1, t += 100'000) {
    if (t % kSecond == 0) m.on_map(corridor_with_a_nook(false, true), t);
    m.on_pose(Pose2{6.5, y, -std::numbers::pi / 2}, t);
    out = step_with_inline_planning(m, t);
    ASSERT_FALSE(is_finished(out.phase)) << out.status;
    if (out.phase == Phase::kSelecting) fastest = std::max(fastest, out.command.v_mps);
  }
  EXPECT_GT(fastest, 0.1);  // it drove itself back
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  EXPECT_GT(out.goal->x(), 19.0);

  // Without the way back the mission ends there, the corridor unexplored.
  o.back_out_m = 0.0;
  Mission shut(o);
  shut_in_the_nook(shut, t, at);
  out = stand_in_the_shut_nook(shut, t, at, 5, mission_finished);
  EXPECT_EQ(out.phase, Phase::kDoneWithUnreachable) << out.status;
  EXPECT_EQ(out.backs_out, 0);
}

TEST(Mission, BacksOutOnceFromOnePlace) {
  MissionOptions o = test_options();
  o.look_around = false;
  Mission m(o);
  std::int64_t t = 0;
  Pose2 at;
  MissionOutput out;
  ASSERT_NO_FATAL_FAILURE(start_backing_out_of_the_shut_nook(m, t, at, out));
  // Before the robot has moved, the door opens on a newer map: a goal.
  t += kSecond;
  m.on_map(corridor_with_a_nook(true, true), t);
  m.on_pose(at, t);
  out = step_with_inline_planning(m, t);
  ASSERT_EQ(out.phase, Phase::kMoving) << out.status;
  // It shuts again: the goal is blocked, and from the place it backed out
  // from the robot does not back out again; the mission ends.
  out = stand_in_the_shut_nook(m, t, at, 15, mission_finished);
  EXPECT_EQ(out.phase, Phase::kDoneWithUnreachable) << out.status;
  EXPECT_EQ(out.backs_out, 1);
}

// The robot does not move on its way back (held by what the mission does
// not see: a drive, the scan guard): the way back ends at its deadline and
// the mission with it, rather than backing out for ever (intel, daemons,
// 2026-11-27: 6000 s in SELECTING "backing out", the robot standing still).
TEST(Mission, AWayBackThatGetsNowhereEndsTheMission) {
  MissionOptions o = test_options();
  o.look_around = false;
  Mission m(o);
  std::int64_t t = 0;
  Pose2 at;
  MissionOutput out;
  ASSERT_NO_FATAL_FAILURE(start_backing_out_of_the_shut_nook(m, t, at, out));
  const std::int64_t began = t;
  out = stand_in_the_shut_nook(m, t, at, 600, mission_finished);
  EXPECT_EQ(out.phase, Phase::kDoneWithUnreachable) << out.status;
  EXPECT_EQ(out.backs_out, 1);
  // Its deadline: the progress timeout and four times the way at full speed
  // (the way back here is the 3 m it came in by).
  EXPECT_LT(t - began, o.progress_timeout_us + static_cast<std::int64_t>(4e6 * 20.0 / o.follower.max_speed_mps));
}

TEST(Mission, AnswersToOldPlanRequestsAreIgnored) {
  Mission m(test_options());
  m.on_map(corridor(false, true), 0);
  m.on_pose(Pose2{10, 1.5, 0}, 0);
  auto out = m.step(0);
  ASSERT_TRUE(out.plan_request.has_value());
  const PlanRequest old = *out.plan_request;
  // Unanswered past plan_timeout_us: asked again with a new id.
  m.on_pose(Pose2{10, 1.5, 0}, 6 * kSecond);
  m.on_map(corridor(false, true), 6 * kSecond);
  out = m.step(6 * kSecond);
  ASSERT_TRUE(out.plan_request.has_value());
  EXPECT_NE(out.plan_request->id, old.id);
  m.on_plan(compute_plan(old), 6 * kSecond);
  EXPECT_EQ(m.step(6 * kSecond + 1).phase, Phase::kSelecting);
  m.on_plan(compute_plan(*out.plan_request), 6 * kSecond + 2);
  EXPECT_EQ(m.step(6 * kSecond + 3).phase, Phase::kMoving);
}

}  // namespace
}  // namespace pex::planning
