#include "planning/exploration_planner.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <map>

#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

using E = mapping::EdgeType;
using testing::typed_polygon;

// A corridor 20 x 3 m and, through a door at x 15..15.5 seen at a grazing
// angle, a 4 x 3 m piece of the room behind it: the free neck between them is
// 0.5 m wide, narrower than the robot, so the room's C-space is cut off from
// the corridor's. The room's far side (y = 7) and the neck's sides are frontier.
mapping::TypedMultiPolygon corridor_with_a_room_seen_through_a_door() {
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(20, 0), Point(20, 3), Point(15.5, 3), Point(15.5, 4), Point(18, 4), Point(18, 7),
       Point(14, 7), Point(14, 4), Point(15, 4), Point(15, 3), Point(0, 3)},
      {E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kFrontier,
       E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}})};
}

PlannerOptions options() {
  PlannerOptions o;
  o.cspace.robot_radius_m = 0.27;
  o.cspace.clearance_margin_m = 0.05;
  o.turn_cost_m_per_rad = 0.0;
  return o;
}

TEST(PlanExploration, AFrontierCutOffFromTheRobotIsApproachedFromWhereItIsInView) {
  const auto map = corridor_with_a_room_seen_through_a_door();
  const Plan plan = plan_exploration(map, Pose2{2, 1.5, 0}, {}, options());
  ASSERT_TRUE(plan.ok) << plan.error;
  // The room's far frontier (y = 7) gets a candidate that the robot can reach:
  // in the corridor, in front of the door, with the frontier point in view.
  const GoalCandidate* far = nullptr;
  for (const auto& c : plan.candidates)
    if (c.frontier_point.y() > 6.9) far = &c;
  ASSERT_NE(far, nullptr);
  EXPECT_TRUE(far->approach);
  EXPECT_TRUE(far->reachable);
  EXPECT_LT(far->position.y(), 3.0);
  EXPECT_GT(far->position.x(), 14.0);
  EXPECT_LT(far->position.x(), 16.5);
  EXPECT_GE(plan.stats.approach_candidates, 1);
  EXPECT_EQ(plan.stats.candidates_not_in_cspace, 0);
  EXPECT_EQ(plan.reachable_count(), static_cast<int>(plan.candidates.size()));
}

TEST(PlanExploration, WithoutApproachTheSameFrontierHasNoPath) {
  // The cause the approach fixes: the C-space next to the frontier is another piece.
  PlannerOptions o = options();
  o.approach_range_m = 0.0;
  const Plan plan = plan_exploration(corridor_with_a_room_seen_through_a_door(), Pose2{2, 1.5, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  bool unreachable_far = false;
  for (const auto& c : plan.candidates)
    if (c.frontier_point.y() > 6.9) unreachable_far = !c.reachable;
  EXPECT_TRUE(unreachable_far);
  EXPECT_TRUE(margin_may_block(plan));
}

TEST(PlanExploration, SaysWhenTheRobotIsInALesserPieceOfTheCSpace) {
  const auto map = corridor_with_a_room_seen_through_a_door();  // the room cut off by its 0.5 m neck
  const Plan corridor = plan_exploration(map, Pose2{2, 1.5, 0}, {}, options());
  ASSERT_TRUE(corridor.ok) << corridor.error;
  EXPECT_FALSE(corridor.stats.robot_in_a_lesser_piece);
  const Plan room = plan_exploration(map, Pose2{16, 5.5, 0}, {}, options());
  ASSERT_TRUE(room.ok) << room.error;
  EXPECT_TRUE(room.stats.robot_in_a_lesser_piece);
}

TEST(PlanExploration, ACandidateInAnotherPieceOfTheCSpaceIsNotSearchedFor) {
  // No path can reach it: a search for it would settle the robot's whole
  // piece (on a large map, the plan's worst time) and find nothing.
  PlannerOptions o = options();
  o.approach_range_m = 0.0;
  const auto map = testing::a_room_cut_off_behind_a_slit();
  const Pose2 robot{1, 1, 0};
  // Greedy and the tour over the nearest candidates (the tour over all of
  // them computes every path from the start in one search anyway).
  for (auto strategy : {GoalStrategy::kGreedy, GoalStrategy::kTour}) {
    o.strategy = strategy;
    o.tour.horizon_candidates = 4;
    const Plan plan = plan_exploration(map, robot, {}, o);
    ASSERT_TRUE(plan.ok) << plan.error;
    ASSERT_EQ(plan.candidates.size(), 1u);
    EXPECT_GT(plan.candidates[0].position.x(), 11.0);
    EXPECT_FALSE(plan.candidates[0].reachable);
    EXPECT_EQ(plan.best, -1);
    EXPECT_EQ(plan.stats.segment_tests, 0);
    // Nor when it is the goal the robot follows.
    const GoalFocus focus{plan.candidates[0].position, plan.candidates[0].frontier_point, 0.5};
    const Plan followed = plan_exploration(map, robot, {}, o, nullptr, &focus);
    ASSERT_TRUE(followed.ok) << followed.error;
    EXPECT_FALSE(followed.candidates.at(0).reachable);
    EXPECT_EQ(followed.stats.segment_tests, 0);
  }
  // The same room with the slit widened: the candidate is searched for and reached.
  auto open = testing::a_room_cut_off_behind_a_slit();
  for (auto& p : open[0].geometry.outer()) {
    if (std::abs(p.y() - 1.85) < 1e-9) p.y(1.2);
    if (std::abs(p.y() - 2.15) < 1e-9) p.y(2.8);
  }
  o.strategy = GoalStrategy::kGreedy;
  const Plan plan = plan_exploration(open, robot, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_EQ(plan.candidates.size(), 1u);
  EXPECT_TRUE(plan.candidates[0].reachable);
  EXPECT_EQ(plan.best, 0);
  EXPECT_GT(plan.stats.segment_tests, 0);
}

TEST(PlanExploration, NoApproachThroughAWall) {
  // The same room behind a solid wall (no neck): its frontier is not in view
  // from the corridor, so there is no approach point and no candidate for it.
  const mapping::TypedMultiPolygon map = {
      typed_polygon(testing::rectangle(0, 0, 20, 3, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle})),
      typed_polygon(testing::rectangle(14, 4, 18, 7, {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle}))};
  const Plan plan = plan_exploration(map, Pose2{2, 1.5, 0}, {}, options());
  ASSERT_TRUE(plan.ok) << plan.error;
  for (const auto& c : plan.candidates) {
    if (c.frontier_point.y() < 6.9) continue;
    EXPECT_FALSE(c.approach);
    EXPECT_FALSE(c.reachable);
  }
}

// A room seen through its 1 m door: a strip 3 m deep below the corridor, its
// far side frontier, and a cabinet (0.3 x 0.2 m) just before the middle of
// that frontier. No place the robot can stand sees the middle past the
// cabinet, but the rest of the frontier is in view from the strip (ring2,
// session 55: the candidate at the middle was out of view, the room never
// entered).
TEST(PlanExploration, AFrontierWhoseMiddleIsHiddenIsApproachedWhereItIsInView) {
  const mapping::TypedMultiPolygon map = {typed_polygon(
      {{Point(0, 0), Point(4, 0), Point(4, -3), Point(5, -3), Point(5, 0), Point(10, 0), Point(10, 2), Point(0, 2)},
       {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle,
        E::kObstacle}},
      {testing::rectangle_hole(4.35, -2.95, 4.65, -2.75)})};
  const Plan plan = plan_exploration(map, Pose2{2, 1, 0}, {}, options());
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.candidates_out_of_view, 0);
  EXPECT_EQ(plan.stats.approached_off_middle, 1);
  ASSERT_EQ(plan.candidates.size(), 1u);
  const GoalCandidate& c = plan.candidates[0];
  EXPECT_TRUE(c.approach);
  EXPECT_NEAR(c.frontier_point.y(), -3.0, 1e-9);
  EXPECT_GT(std::abs(c.frontier_point.x() - 4.5), 0.2);  // not the middle, which the cabinet hides
  EXPECT_TRUE(c.reachable);
  EXPECT_LT(c.position.y(), 0.0);  // in the strip, beyond the door
}

// A sliver of free space behind the corridor's top wall, 0.1 m wide and 4 m
// long, its far side frontier (what a scan seen through a gap, or a scan
// placed a little off, leaves beyond a thin wall). Its frontier is 0.47 m
// from the corridor's C-space, within the snap distance; the wall is between.
TEST(PlanExploration, AFrontierBehindAWallIsOutOfViewNotAGoal) {
  const mapping::TypedMultiPolygon map = {
      typed_polygon(testing::rectangle(0, 0, 20, 3)),
      typed_polygon(testing::rectangle(5, 3.05, 9, 3.15, {E::kObstacle, E::kFrontier, E::kFrontier, E::kFrontier}))};
  const Plan plan = plan_exploration(map, Pose2{2, 1.5, 0}, {}, options());
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.best_candidate(), nullptr);  // without the check: a goal in the corridor facing the wall
  EXPECT_TRUE(plan.candidates.empty());
  EXPECT_EQ(plan.stats.candidates_out_of_view, 1);
  ASSERT_EQ(plan.out_of_view_frontier_points.size(), 1u);
  EXPECT_GT(plan.out_of_view_frontier_points[0].y(), 3.0);
  EXPECT_EQ(plan.stats.candidates_not_in_cspace, 0);

  // The same sliver 1.5 m beyond the wall, farther than the snap distance
  // from the corridor's C-space: out of view too, not "too narrow".
  const mapping::TypedMultiPolygon farther = {
      typed_polygon(testing::rectangle(0, 0, 20, 3)),
      typed_polygon(testing::rectangle(5, 4.4, 9, 4.5, {E::kObstacle, E::kFrontier, E::kFrontier, E::kFrontier}))};
  const Plan far_plan = plan_exploration(farther, Pose2{2, 1.5, 0}, {}, options());
  ASSERT_TRUE(far_plan.ok) << far_plan.error;
  EXPECT_EQ(far_plan.stats.candidates_out_of_view, 1);
  EXPECT_EQ(far_plan.stats.candidates_not_in_cspace, 0);
  // Frontiers in view of their C-space point stay goals: the windows of
  // corridor_with_windows() below.
}

// A corridor 30 x 3 m whose top wall has 1 m windows of frontier at x = 8,
// 11 and 15. From x = 10 the nearest is 11; but 8, 11, 15 in that order is
// the shorter way through all three (9 m against 11 m for 11, 8, 15).
mapping::TypedMultiPolygon corridor_with_windows(double length_m = 30.0,
                                                 const std::vector<double>& windows_x = {15.0, 11.0, 8.0}) {
  std::vector<Point> pts = {Point(0, 0), Point(length_m, 0), Point(length_m, 3)};
  std::vector<E> types = {E::kObstacle, E::kObstacle, E::kObstacle};
  for (double x : windows_x) {  // right to left, as the ring goes
    pts.push_back(Point(x + 0.5, 3));
    types.push_back(E::kFrontier);
    pts.push_back(Point(x - 0.5, 3));
    types.push_back(E::kObstacle);
  }
  pts.push_back(Point(0, 3));
  types.push_back(E::kObstacle);
  return {typed_polygon(testing::RingSpec{pts, types})};
}

// A 10 x 10 m room, its top side frontier (unbounded unknown beyond), with
// a 2 x 1 m desk whose right side the laser has not seen: the unknown behind
// that frontier is the desk's 2 m2 at most.
mapping::TypedMultiPolygon room_with_a_desk_seen_from_three_sides() {
  auto desk = testing::rectangle_hole(4, 4, 6, 5);
  desk.types = {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle};
  return {typed_polygon(testing::rectangle(0, 0, 10, 10, {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle}),
                        {desk})};
}

TEST(PlanExploration, AFrontierOnASmallEnclosedUnknownIsNoGoal) {
  const auto map = room_with_a_desk_seen_from_three_sides();
  auto desk_candidate = [](const Plan& plan) {
    return std::find_if(plan.candidates.begin(), plan.candidates.end(),
                        [](const GoalCandidate& c) { return c.frontier_point.y() < 9.0; });
  };
  // Off (0): both frontiers are goals, and the desk's is the nearer.
  PlannerOptions o = options();
  Plan plan = plan_exploration(map, Pose2{8, 4.5, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_EQ(plan.candidates.size(), 2u);
  ASSERT_NE(desk_candidate(plan), plan.candidates.end());
  EXPECT_TRUE(desk_candidate(plan)->reachable);
  EXPECT_NEAR(desk_candidate(plan)->enclosed_area_m2, 2.0, 1e-9);
  EXPECT_EQ(plan.best, static_cast<int>(desk_candidate(plan) - plan.candidates.begin()));
  EXPECT_EQ(plan.stats.candidates_enclosed, 0);
  // Above the desk's area: the desk's frontier is enclosed, the room's top
  // (the unbounded outside) stays a goal however large the bound.
  for (const double min_m2 : {3.0, 1000.0}) {
    o.min_enclosed_area_m2 = min_m2;
    plan = plan_exploration(map, Pose2{8, 4.5, 0}, {}, o);
    ASSERT_TRUE(plan.ok) << plan.error;
    ASSERT_EQ(plan.candidates.size(), 1u) << min_m2;
    EXPECT_GT(plan.candidates[0].frontier_point.y(), 9.9);
    EXPECT_TRUE(std::isinf(plan.candidates[0].enclosed_area_m2));
    EXPECT_EQ(plan.best, 0);
    EXPECT_EQ(plan.stats.candidates_enclosed, 1);
    ASSERT_EQ(plan.enclosed_frontier_points.size(), 1u);
    EXPECT_NEAR(plan.enclosed_frontier_points[0].x(), 6.0, 1e-9);
    EXPECT_FALSE(margin_may_block(plan));
  }
  // Below it: still a goal.
  o.min_enclosed_area_m2 = 1.5;
  plan = plan_exploration(map, Pose2{8, 4.5, 0}, {}, o);
  ASSERT_EQ(plan.candidates.size(), 2u);
  EXPECT_EQ(plan.stats.candidates_enclosed, 0);
}

// A 10 x 10 m room, its top side frontier (unbounded unknown beyond), with a
// 1.6 x 0.8 m desk 5 cm in front of its bottom wall (x 4..5.6) whose left
// flank the laser has not seen: the frontier from the wall up to the desk's
// corner lies in a walled bay of 1.6 x 0.85 m.
mapping::TypedMultiPolygon room_with_a_desk_against_its_wall() {
  using E = mapping::EdgeType;
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(4, 0), Point(4, 0.85), Point(5.6, 0.85), Point(5.6, 0.05), Point(5.6, 0), Point(10, 0),
       Point(10, 10), Point(0, 10)},
      {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle,
       E::kFrontier, E::kObstacle}})};
}

TEST(PlanExploration, AFrontierInASmallWalledBayIsEnclosed) {
  const auto map = room_with_a_desk_against_its_wall();
  auto flank = [](const Plan& plan) {
    return std::find_if(plan.candidates.begin(), plan.candidates.end(),
                        [](const GoalCandidate& c) { return c.frontier_point.y() < 1.0; });
  };
  PlannerOptions o = options();
  o.min_enclosed_area_m2 = 2.0;
  o.enclosed_goal_range_m = 4.0;
  // Without bays: the flank (7.2 m away) is a goal, the nearest.
  Plan plan = plan_exploration(map, Pose2{8, 6, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_NE(flank(plan), plan.candidates.end());
  EXPECT_TRUE(std::isinf(flank(plan)->enclosed_area_m2));
  EXPECT_EQ(plan.stats.candidates_enclosed, 0);
  // With them: enclosed, and the room's top is the goal.
  o.bay_max_area_m2 = 3.0;
  plan = plan_exploration(map, Pose2{8, 6, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(flank(plan), plan.candidates.end());
  EXPECT_EQ(plan.stats.candidates_enclosed, 1);
  ASSERT_EQ(plan.enclosed_frontier_points.size(), 1u);
  EXPECT_LT(plan.enclosed_frontier_points[0].y(), 1.0);
  ASSERT_GE(plan.best, 0);
  EXPECT_GT(plan.candidates[static_cast<std::size_t>(plan.best)].frontier_point.y(), 9.9);
  // Within enclosed_goal_range_m of the robot it is still a goal, with the bay's area.
  plan = plan_exploration(map, Pose2{3, 2.5, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_NE(flank(plan), plan.candidates.end());
  EXPECT_NEAR(flank(plan)->enclosed_area_m2, 1.6 * 0.85, 1e-9);
  // A bay of the desk's size or more is not looked for.
  o.bay_max_area_m2 = 1.3;
  plan = plan_exploration(map, Pose2{8, 6, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_NE(flank(plan), plan.candidates.end());
  // Nor without the enclosed rule itself.
  o.bay_max_area_m2 = 3.0;
  o.min_enclosed_area_m2 = 0.0;
  plan = plan_exploration(map, Pose2{8, 6, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_NE(flank(plan), plan.candidates.end());
}

TEST(PlanExploration, AnEnclosedFrontierNearTheRobotOrFollowedIsStillAGoal) {
  const auto map = room_with_a_desk_seen_from_three_sides();  // the desk's frontier at x = 6, y 4..5
  PlannerOptions o = options();
  o.min_enclosed_area_m2 = 3.0;
  o.enclosed_goal_range_m = 4.0;
  // 2 m from the robot: a look on the way, a goal (the nearest).
  Plan plan = plan_exploration(map, Pose2{8, 4.5, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.candidates.size(), 2u);
  EXPECT_EQ(plan.stats.candidates_enclosed, 0);
  // 6.7 m away: enclosed.
  plan = plan_exploration(map, Pose2{1, 9, 0}, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.candidates.size(), 1u);
  EXPECT_EQ(plan.stats.candidates_enclosed, 1);
  // ... unless it is the goal the robot follows.
  GoalFocus focus;
  focus.frontier = Point(6.0, 4.5);
  focus.goal = Point(6.5, 4.5);
  focus.radius_m = 1.0;
  plan = plan_exploration(map, Pose2{1, 9, 0}, {}, o, nullptr, &focus);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_EQ(plan.candidates.size(), 2u);
  EXPECT_EQ(plan.stats.candidates_enclosed, 0);
  for (const auto& c : plan.candidates) {
    if (c.frontier_point.y() < 9.0) {
      EXPECT_TRUE(std::isfinite(c.path_length_m)) << "the followed goal's path";
    }
  }
}

// The planner with the pocket test on (PlannerOptions::reach_past_frontier_m).
PlannerOptions pocket_options() {
  PlannerOptions o = options();
  o.reach_past_frontier_m = 0.02;
  return o;
}

// A 6 x 4 m room whose top wall has a slot `slot_width_m` wide and 0.8 m
// deep from x = 3 (0.2 m: the gap between two desks against a wall): the
// laser saw into it from below, its right side and back are walls, and the
// shadow of the slot's left corner is a frontier from (3, 4) to the back.
mapping::TypedMultiPolygon room_with_a_slot(double slot_width_m) {
  const double right = 3.0 + slot_width_m;
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(6, 0), Point(6, 4), Point(right, 4), Point(right, 4.8), Point(right - 0.05, 4.8),
       Point(3, 4), Point(0, 4)},
      {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle,
       E::kObstacle}})};
}

TEST(PlanExploration, AFrontierInAGapNarrowerThanTheRobotIsAPocketNotAGoal) {
  const auto map = room_with_a_slot(0.2);
  const Plan plan = plan_exploration(map, Pose2{1, 2, 0}, {}, pocket_options());
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_TRUE(plan.candidates.empty());
  EXPECT_EQ(plan.best, -1);
  EXPECT_EQ(plan.stats.candidates_in_pockets, 1);
  ASSERT_EQ(plan.pocket_frontier_points.size(), 1u);
  EXPECT_NEAR(plan.pocket_frontier_points[0].y(), 4.4, 0.01);
  EXPECT_FALSE(margin_may_block(plan));  // planning without the margin is not asked for
  // The cause: without the test the slot's frontier is a goal, and a
  // reachable one (the robot would stand below the slot and look in).
  PlannerOptions off = pocket_options();
  off.reach_past_frontier_m = 0.0;
  const Plan without = plan_exploration(map, Pose2{1, 2, 0}, {}, off);
  ASSERT_EQ(without.candidates.size(), 1u);
  EXPECT_TRUE(without.candidates[0].reachable);
  EXPECT_EQ(without.stats.candidates_in_pockets, 0);
}

TEST(PlanExploration, ASlotTheRobotFitsInIsNoPocket) {
  // 0.8 m wide: the robot (0.54 m) drives in and sees past the frontier.
  const Plan plan = plan_exploration(room_with_a_slot(0.8), Pose2{1, 2, 0}, {}, pocket_options());
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.candidates_in_pockets, 0);
  ASSERT_EQ(plan.candidates.size(), 1u);
  EXPECT_TRUE(plan.candidates[0].reachable);
}

TEST(PlanExploration, ASlotTheMarginClosesIsNoPocket) {
  // 0.6 m wide: no C-space inside (it needs 2 x (0.27 + 0.05) m), but the
  // robot's disk (0.54 m) fits into its mouth and reaches past the frontier.
  const Plan plan = plan_exploration(room_with_a_slot(0.6), Pose2{1, 2, 0}, {}, pocket_options());
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.candidates_in_pockets, 0);
  ASSERT_EQ(plan.candidates.size(), 1u);
  EXPECT_TRUE(plan.candidates[0].reachable);
}

TEST(PlanExploration, ADoorNarrowerThanTheRobotIsNoPocket) {
  // A doorway 0.45 m wide in the top wall, unknown beyond it: the robot
  // does not pass, but its disk reaches into the doorway, past the frontier
  // across it, so the door stays a goal (and the mission does not call the
  // space beyond it explored).
  const mapping::TypedMultiPolygon map = {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(6, 0), Point(6, 4), Point(3.45, 4), Point(3, 4), Point(0, 4)},
      {E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}})};
  const Plan plan = plan_exploration(map, Pose2{1, 2, 0}, {}, pocket_options());
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.candidates_in_pockets, 0);
  ASSERT_EQ(plan.candidates.size(), 1u);
  EXPECT_TRUE(plan.candidates[0].reachable);
}

// With no goal left and no margin, a frontier in a room the robot reaches
// only through a gap narrower than itself (by more than
// narrow_gap_tolerance_m) is behind a narrow gap: no candidate, listed. A
// gap within the tolerance of the robot's width (the map's noise may have
// narrowed a passage it fits) is approached at its mouth, once. A plan with
// the margin (whose tight plan decides) and a robot in the lesser part of
// the map (shut in a nook: the mission backs out first) leave it a
// candidate without a path.
PlannerOptions narrow_gap_options(double clearance_margin_m) {
  PlannerOptions o = options();  // robot radius 0.27 m: 0.54 m across
  o.cspace.clearance_margin_m = clearance_margin_m;
  o.narrow_gap_tolerance_m = 0.05;  // gaps under 0.44 m
  return o;
}

// A hall 20 x 4 m (x = -10 to 10) and, through the gap, a room whose far wall is frontier.
mapping::TypedMultiPolygon a_room_off_a_hall(double gap_m) {
  return testing::a_room_behind_a_gap(gap_m, -10.0, E::kObstacle, E::kFrontier);
}

int candidates_without_a_path(const Plan& plan) {
  int n = 0;
  for (const auto& c : plan.candidates) n += !c.reachable;
  return n;
}

TEST(PlanExploration, AFrontierBehindAGapNarrowerThanTheRobotIsNoCandidate) {
  const Plan plan = plan_exploration(a_room_off_a_hall(0.3), Pose2{2, 2, 0}, {}, narrow_gap_options(0.0));
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.best, -1);
  EXPECT_TRUE(plan.candidates.empty());
  ASSERT_GE(plan.stats.candidates_behind_narrow_gaps, 1);
  ASSERT_EQ(plan.behind_narrow_gap_points.size(), static_cast<std::size_t>(plan.stats.candidates_behind_narrow_gaps));
  for (const auto& p : plan.behind_narrow_gap_points) EXPECT_NEAR(p.x(), 22.0, 1e-6);
}

// The frontier at the slot's end is seen from the room's C-space only, more
// than candidate_snap_distance_m away: a candidate there without a path (no
// longer "too narrow", which kept the mission from DONE), and in the endgame
// the narrower disk settles it as for any candidate without a path.
TEST(PlanExploration, AFrontierSeenOnlyFromAfarInARoomTheRobotCannotEnterIsBehindTheGap) {
  const Pose2 robot{2, 2, 0};
  PlannerOptions with_margin = options();
  with_margin.narrow_gap_tolerance_m = 0.05;
  const Plan first = plan_exploration(testing::a_slot_in_a_room_behind_a_gap(0.3), robot, {}, with_margin);
  ASSERT_TRUE(first.ok) << first.error;
  EXPECT_EQ(first.best, -1);
  EXPECT_EQ(first.stats.candidates_not_in_cspace, 0);
  EXPECT_TRUE(first.narrow_frontier_points.empty());
  EXPECT_EQ(first.stats.candidates_seen_from_afar, 1);
  ASSERT_EQ(first.candidates.size(), 1u);
  const GoalCandidate& c = first.candidates[0];
  EXPECT_FALSE(c.reachable);
  EXPECT_FALSE(c.approach);
  EXPECT_NEAR(c.frontier_point.y(), 6.0, 1e-6);
  EXPECT_NEAR(c.position.x(), 16.21, 0.05);  // below the slot, in the room
  EXPECT_LT(c.position.y(), 4.0);
  EXPECT_GT(distance(c.position, c.frontier_point), with_margin.candidate_snap_distance_m);
  EXPECT_TRUE(margin_may_block(first));  // the mission plans again without the margin

  // The plan without the margin: the room is apart for the narrower disk too.
  const Plan tight = plan_exploration(testing::a_slot_in_a_room_behind_a_gap(0.3), robot, {}, narrow_gap_options(0.0));
  ASSERT_TRUE(tight.ok) << tight.error;
  EXPECT_EQ(tight.best, -1);
  EXPECT_TRUE(tight.candidates.empty());
  ASSERT_EQ(tight.behind_narrow_gap_points.size(), 1u);
  EXPECT_NEAR(tight.behind_narrow_gap_points[0].y(), 6.0, 1e-6);

  // A gap about the robot's width: looked through from its mouth, as the room's other frontiers are.
  const Plan mouth = plan_exploration(testing::a_slot_in_a_room_behind_a_gap(0.5), robot, {}, narrow_gap_options(0.0));
  ASSERT_TRUE(mouth.ok) << mouth.error;
  const GoalCandidate* goal = mouth.best_candidate();
  ASSERT_NE(goal, nullptr);
  EXPECT_TRUE(goal->gap_mouth && goal->reachable);
  EXPECT_NEAR(goal->frontier_point.y(), 6.0, 1e-6);
  EXPECT_LT(goal->position.x(), 10.0);  // in the hall, before the gap
}

TEST(PlanExploration, AFrontierBehindAGapAboutTheRobotsWidthIsApproachedAtTheGapsMouth) {
  // 0.50 m: the robot (0.54 m) does not pass, a disk 0.44 m across does.
  const Pose2 robot{2, 2, 0};
  const PlannerOptions o = narrow_gap_options(0.0);
  const Plan plan = plan_exploration(a_room_off_a_hall(0.5), robot, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.candidates_behind_narrow_gaps, 0);
  EXPECT_EQ(candidates_without_a_path(plan), 0);
  EXPECT_EQ(plan.stats.gap_mouth_candidates, static_cast<int>(plan.candidates.size()));
  const GoalCandidate* goal = plan.best_candidate();
  ASSERT_NE(goal, nullptr);
  EXPECT_TRUE(goal->gap_mouth && goal->approach && goal->reachable);
  EXPECT_NEAR(goal->frontier_point.x(), 22.0, 1e-6);  // what it is for: the room's far wall
  // The gap runs x = 10..11, y = 1.75..2.25: the robot stands before it in the hall.
  EXPECT_GT(goal->position.x(), 9.5);
  EXPECT_LT(goal->position.x(), 10.0);
  EXPECT_NEAR(goal->position.y(), 2.0, 0.2);
  ASSERT_GE(goal->path.size(), 2u);
  EXPECT_EQ(distance(goal->path.back(), goal->position), 0.0);
  EXPECT_NEAR(goal->path_length_m, distance(Point(2, 2), goal->position), 1e-6);  // a straight run along the hall
  // The robot's disk fits everywhere on the way (the C-space of the plan, not the narrower one).
  ConfigurationSpace cspace;
  ASSERT_TRUE(cspace.build(a_room_off_a_hall(0.5), o.cspace).ok);
  for (std::size_t k = 0; k + 1 < goal->path.size(); ++k)
    for (double t = 0.0; t <= 1.0; t += 0.05)
      EXPECT_TRUE(cspace.covers(Point(goal->path[k].x() + t * (goal->path[k + 1].x() - goal->path[k].x()),
                                      goal->path[k].y() + t * (goal->path[k + 1].y() - goal->path[k].y()))));

  // Once: the mouth reached (blacklisted), no goal is left and none is "behind a gap".
  const Plan again = plan_exploration(a_room_off_a_hall(0.5), robot, {goal->position}, o);
  ASSERT_TRUE(again.ok) << again.error;
  EXPECT_EQ(again.best, -1);
  EXPECT_EQ(again.stats.candidates_behind_narrow_gaps, 0);
  ASSERT_FALSE(again.candidates.empty());
  for (const auto& c : again.candidates) EXPECT_TRUE(c.gap_mouth && c.blacklisted);
}

// A gap about the robot's width is the last resort: while another goal is
// reachable its frontiers stay without a path, unless one of them is the
// goal the robot follows (the plan's focus), which keeps its way to the mouth.
TEST(PlanExploration, AGapsMouthIsAGoalOnlyWhenNoneIsLeftOrWhenItIsTheGoalFollowed) {
  const auto map = testing::a_room_behind_a_gap(0.5, -10.0, E::kFrontier, E::kFrontier);
  const Pose2 robot{2, 2, 0};
  const PlannerOptions o = narrow_gap_options(0.0);
  const Plan plan = plan_exploration(map, robot, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_NE(plan.best_candidate(), nullptr);
  EXPECT_LT(plan.best_candidate()->frontier_point.x(), -9.9);  // the hall's west end
  EXPECT_EQ(plan.stats.gap_mouth_candidates, 0);
  EXPECT_GE(candidates_without_a_path(plan), 1);

  const Plan alone = plan_exploration(a_room_off_a_hall(0.5), robot, {}, o);
  ASSERT_NE(alone.best_candidate(), nullptr);
  const GoalFocus focus{alone.best_candidate()->position, alone.best_candidate()->frontier_point, 1.5};
  const Plan followed = plan_exploration(map, robot, {}, o, nullptr, &focus);
  ASSERT_TRUE(followed.ok) << followed.error;
  int matched = 0;
  for (const auto& c : followed.candidates) {
    if (!focus.matches(c)) continue;
    ++matched;
    EXPECT_TRUE(c.gap_mouth && c.reachable);
    EXPECT_NEAR(distance(c.position, focus.goal), 0.0, 1e-6);
  }
  EXPECT_GE(matched, 1);
}

TEST(PlanExploration, APlanWithTheMarginOrTheToleranceOffLeavesTheFrontierWithoutAPath) {
  const auto map = a_room_off_a_hall(0.3);
  const Plan with_margin = plan_exploration(map, Pose2{2, 2, 0}, {}, narrow_gap_options(0.05));
  ASSERT_TRUE(with_margin.ok) << with_margin.error;
  EXPECT_EQ(with_margin.stats.candidates_behind_narrow_gaps, 0);
  EXPECT_GE(candidates_without_a_path(with_margin), 1);
  EXPECT_TRUE(margin_may_block(with_margin));  // the tight plan decides
  PlannerOptions off = narrow_gap_options(0.0);
  off.narrow_gap_tolerance_m = 0.0;
  const Plan plan = plan_exploration(map, Pose2{2, 2, 0}, {}, off);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.candidates_behind_narrow_gaps, 0);
  EXPECT_GE(candidates_without_a_path(plan), 1);
}

TEST(PlanExploration, ARobotInTheLesserPartOfTheMapLeavesTheFrontierWithoutAPath) {
  // The robot in the 44 m2 room, the frontier on the 80 m2 hall's far wall.
  const auto map = testing::a_room_behind_a_gap(0.3, -10.0, E::kFrontier, E::kObstacle);
  const Plan plan = plan_exploration(map, Pose2{16, 2, 0}, {}, narrow_gap_options(0.0));
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.candidates_behind_narrow_gaps, 0);
  EXPECT_GE(candidates_without_a_path(plan), 1);
  EXPECT_TRUE(plan.stats.robot_in_a_lesser_piece);
}

// A 10 x 4 m room, its east wall a frontier, with a 0.8 m square chamber
// north of it, joined by a neck 0.5 m wide and 0.2 m long: the chamber's
// C-space (0.32 m offset) is a speck of about 0.03 m2 of its own, the
// room's comes to 0.2 m below the neck.
mapping::TypedMultiPolygon a_room_with_a_speck_beside_the_robot() {
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(10, 0), Point(10, 4), Point(5.25, 4), Point(5.25, 4.2), Point(5.4, 4.2), Point(5.4, 5.0),
       Point(4.6, 5.0), Point(4.6, 4.2), Point(4.75, 4.2), Point(4.75, 4), Point(0, 4)},
      {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle,
       E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle}})};
}

TEST(PlanExploration, TheRobotsStartIsNotASliverOfCSpaceBesideIt) {
  // The robot in the neck, 0.25 m from the speck and 0.35 m from the room's
  // C-space (found on floor90: a 0.03 m2 speck 2 cm from the robot, every
  // goal "no path", the goal followed given up).
  const auto map = a_room_with_a_speck_beside_the_robot();
  const Pose2 robot{5.0, 4.15, -M_PI / 2};
  PlannerOptions o = options();
  o.start_sliver_area_m2 = 0.0;
  const Plan stranded = plan_exploration(map, robot, {}, o);
  ASSERT_TRUE(stranded.ok) << stranded.error;
  EXPECT_EQ(stranded.best_candidate(), nullptr);
  EXPECT_GE(candidates_without_a_path(stranded), 1);

  o.start_sliver_area_m2 = 0.05;
  const Plan plan = plan_exploration(map, robot, {}, o);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.start_sliver_skipped, 1);
  ASSERT_NE(plan.best_candidate(), nullptr);
  EXPECT_EQ(candidates_without_a_path(plan), 0);
  const auto& path = plan.best_candidate()->path;
  ASSERT_GE(path.size(), 2u);
  // From the robot down into the room, not up into the chamber.
  EXPECT_LT(path[1].y(), 3.85);
  EXPECT_NEAR(plan.best_candidate()->frontier_point.x(), 10.0, 1e-6);
}

TEST(PlanExploration, TheRobotsStartStaysInASliverWhenAWallStandsBeforeTheLargerPiece) {
  // The same chamber as a map polygon of its own behind a 5 cm wall: the
  // room's C-space is within the snap distance, but not through the wall.
  auto map = mapping::TypedMultiPolygon{typed_polygon(testing::rectangle(
      0, 0, 10, 4, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))};
  map.push_back(typed_polygon(testing::rectangle(4.6, 4.05, 5.4, 4.85)));
  const Plan plan = plan_exploration(map, Pose2{5.0, 4.06, 0.0}, {}, options());
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.stats.start_sliver_skipped, 0);
  EXPECT_EQ(plan.best_candidate(), nullptr);
  EXPECT_GE(candidates_without_a_path(plan), 1);
}

TEST(PlanExploration, TourStrategyPlansTheOrderNotJustTheNearest) {
  PlannerOptions o = options();
  o.strategy = GoalStrategy::kGreedy;
  const Pose2 robot{10, 2.5, 0};
  const Plan greedy = plan_exploration(corridor_with_windows(), robot, {}, o);
  ASSERT_TRUE(greedy.ok) << greedy.error;
  ASSERT_NE(greedy.best_candidate(), nullptr);
  EXPECT_NEAR(greedy.best_candidate()->frontier_point.x(), 11.0, 0.01);
  EXPECT_TRUE(greedy.tour.empty());

  o.strategy = GoalStrategy::kTour;
  const Plan tour = plan_exploration(corridor_with_windows(), robot, {}, o);
  ASSERT_TRUE(tour.ok) << tour.error;
  ASSERT_NE(tour.best_candidate(), nullptr);
  EXPECT_NEAR(tour.best_candidate()->frontier_point.x(), 8.0, 0.01);
  ASSERT_EQ(tour.tour.size(), 3u);
  EXPECT_NEAR(tour.candidates[static_cast<std::size_t>(tour.tour[1])].frontier_point.x(), 11.0, 0.01);
  EXPECT_NEAR(tour.candidates[static_cast<std::size_t>(tour.tour[2])].frontier_point.x(), 15.0, 0.01);
  // The same paths either way, where greedy searched them: only the choice
  // differs. Greedy stops at its goal: a candidate it did not search is
  // reachable, without a path, and no cheaper than its goal.
  int unsearched = 0;
  for (std::size_t i = 0; i < tour.candidates.size(); ++i) {
    const auto& g = greedy.candidates[i];
    EXPECT_EQ(g.reachable, tour.candidates[i].reachable);
    if (std::isfinite(g.path_length_m)) {
      EXPECT_NEAR(tour.candidates[i].path_length_m, g.path_length_m, 1e-6);
      continue;
    }
    ++unsearched;
    EXPECT_TRUE(g.path.empty());
    EXPECT_GE(tour.candidates[i].path_length_m, greedy.best_candidate()->cost);
  }
  EXPECT_GT(unsearched, 0);

  // The goal being followed gets its path although another is cheaper.
  const auto far = static_cast<std::size_t>(tour.tour[2]);
  o.strategy = GoalStrategy::kGreedy;
  const GoalFocus focus{tour.candidates[far].position, tour.candidates[far].frontier_point, 0.3};
  const Plan followed = plan_exploration(corridor_with_windows(), robot, {}, o, nullptr, &focus);
  EXPECT_EQ(followed.best, greedy.best);
  EXPECT_NEAR(followed.candidates[far].path_length_m, tour.candidates[far].path_length_m, 1e-6);
  EXPECT_FALSE(followed.candidates[far].path.empty());
  o.strategy = GoalStrategy::kTour;

  // Bounded: the tour's first (2 m away) only within 1.5 x the nearest's
  // 1 m + 0.2 m; else the nearest. The order stays the tour's.
  o.tour.max_first_leg_ratio = 1.5;
  o.tour.first_leg_slack_m = 0.2;
  const Plan bounded = plan_exploration(corridor_with_windows(), robot, {}, o);
  ASSERT_NE(bounded.best_candidate(), nullptr);
  EXPECT_NEAR(bounded.best_candidate()->frontier_point.x(), 11.0, 0.01);
  EXPECT_EQ(bounded.tour, tour.tour);
  o.tour.max_first_leg_ratio = 0.0;  // no bound: the tour's first
  EXPECT_NEAR(plan_exploration(corridor_with_windows(), robot, {}, o).best_candidate()->frontier_point.x(), 8.0, 0.01);

  // A blacklisted candidate is not in the tour.
  const Plan without = plan_exploration(corridor_with_windows(), robot, {tour.best_candidate()->position}, o);
  ASSERT_NE(without.best_candidate(), nullptr);
  EXPECT_EQ(without.tour.size(), 2u);
  EXPECT_NEAR(without.best_candidate()->frontier_point.x(), 11.0, 0.01);
}

// A corridor 40 x 3 m with 1 m windows of frontier in its top wall every 4 m.
mapping::TypedMultiPolygon corridor_with_many_windows() {
  return corridor_with_windows(40.0, {38.0, 34.0, 30.0, 26.0, 22.0, 18.0, 14.0, 10.0, 6.0, 2.0});
}

// With a horizon the tour runs over the nearest candidates only, with the
// lengths the whole matrix gives them; the others are reachable without a
// path, except the goal being followed.
TEST(PlanExploration, TourWithAHorizonOrdersTheNearestCandidatesOnly) {
  PlannerOptions o = options();
  o.strategy = GoalStrategy::kTour;
  const Pose2 robot{13, 1.5, 0};
  const auto map = corridor_with_many_windows();
  const Plan all = plan_exploration(map, robot, {}, o);
  ASSERT_TRUE(all.ok) << all.error;
  ASSERT_EQ(all.tour.size(), 10u);
  o.tour.horizon_candidates = 3;
  const Plan near = plan_exploration(map, robot, {}, o);
  ASSERT_TRUE(near.ok) << near.error;
  ASSERT_EQ(near.tour.size(), 3u);
  ASSERT_NE(near.best_candidate(), nullptr);
  // The three nearest by path: the windows at x = 14, 10 and 18.
  std::vector<double> xs;
  for (const int i : near.tour) xs.push_back(near.candidates[static_cast<std::size_t>(i)].frontier_point.x());
  std::sort(xs.begin(), xs.end());
  ASSERT_EQ(xs.size(), 3u);
  EXPECT_NEAR(xs[0], 10.0, 0.01);
  EXPECT_NEAR(xs[1], 14.0, 0.01);
  EXPECT_NEAR(xs[2], 18.0, 0.01);
  int without_path = 0;
  for (std::size_t i = 0; i < near.candidates.size(); ++i) {
    EXPECT_TRUE(near.candidates[i].reachable);
    if (near.candidates[i].path.empty()) {
      ++without_path;
      continue;
    }
    EXPECT_NEAR(near.candidates[i].path_length_m, all.candidates[i].path_length_m, 1e-6);
  }
  EXPECT_GE(without_path, 7);
  // The goal being followed, the window at x = 38, gets its path too.
  std::size_t far = 0;
  for (std::size_t i = 0; i < all.candidates.size(); ++i)
    if (all.candidates[i].frontier_point.x() > all.candidates[far].frontier_point.x()) far = i;
  const GoalFocus focus{all.candidates[far].position, all.candidates[far].frontier_point, 0.3};
  const Plan followed = plan_exploration(map, robot, {}, o, nullptr, &focus);
  EXPECT_EQ(followed.tour, near.tour);
  EXPECT_NEAR(followed.candidates[far].path_length_m, all.candidates[far].path_length_m, 1e-6);
}

// One stop per frontier chain: a 12 m frontier in the corridor's top wall
// has several candidates, of which the tour keeps the cheapest only.
TEST(PlanExploration, TourOnePerChainStopsOnceAtEachFrontier) {
  std::vector<Point> pts = {Point(0, 0), Point(30, 0), Point(30, 3), Point(20.5, 3), Point(19.5, 3),
                            Point(14, 3), Point(2, 3), Point(0, 3)};
  std::vector<E> types = {E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier,
                          E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle};
  const mapping::TypedMultiPolygon map{typed_polygon(testing::RingSpec{pts, types})};
  PlannerOptions o = options();
  o.strategy = GoalStrategy::kTour;
  const Pose2 robot{16, 1.5, 0};
  const Plan every = plan_exploration(map, robot, {}, o);
  ASSERT_TRUE(every.ok) << every.error;
  std::map<int, int> per_chain;
  for (const int i : every.tour) ++per_chain[every.candidates[static_cast<std::size_t>(i)].chain];
  ASSERT_EQ(per_chain.size(), 2u);
  ASSERT_GT(every.tour.size(), 2u);  // the long frontier has more than one candidate

  o.tour.one_per_chain = true;
  const Plan once = plan_exploration(map, robot, {}, o);
  ASSERT_TRUE(once.ok) << once.error;
  ASSERT_EQ(once.tour.size(), 2u);
  EXPECT_NE(once.candidates[static_cast<std::size_t>(once.tour[0])].chain,
            once.candidates[static_cast<std::size_t>(once.tour[1])].chain);
  // Each chain's stop is its cheapest candidate.
  for (const int i : once.tour) {
    const auto& stop = once.candidates[static_cast<std::size_t>(i)];
    for (const auto& c : once.candidates) {
      if (c.chain == stop.chain && c.reachable) {
        EXPECT_LE(stop.cost, c.cost);
      }
    }
  }
}

// A robot in the middle of a slit narrower than itself in the map (it drove
// in: the world's slit is wider), 0.75 m from the C-space, farther than a
// start may snap: without its trail no plan starts; with it, the plan
// starts where it stands and goes back the way it came.
TEST(PlanPathTo, FromFartherOutThanAStartSnapsTheTrailLeadsBack) {
  const auto map = testing::a_room_cut_off_behind_a_slit();
  PlannerOptions o = options();
  o.cspace.clearance_margin_m = 0.0;
  const Pose2 robot{10.5, 2.0, 0.0};
  const Point home(5.0, 1.0);
  const Plan lost = plan_path_to(map, robot, home, o);
  EXPECT_FALSE(lost.ok);
  EXPECT_TRUE(lost.robot_outside_cspace);
  const std::vector<Point> trail{{8.0, 2.0}, {10.5, 2.0}};
  const DrivenWay way{trail, 0.05};
  const Plan plan = plan_path_to(map, robot, home, o, nullptr, &way);
  ASSERT_TRUE(plan.ok) << plan.error;
  ASSERT_EQ(plan.best, 0);
  const auto& path = plan.candidates[0].path;
  ASSERT_GE(path.size(), 2u);
  EXPECT_EQ(distance(path.front(), Point(10.5, 2.0)), 0.0);
  EXPECT_NEAR(path[1].y(), 2.0, 0.05 + 1e-6) << "out along the trail's corridor, not across the slit's walls";
  EXPECT_EQ(distance(path.back(), home), 0.0);
}

TEST(PlanPathTo, FindsThePathHomeOrSaysItIsUnreachable) {
  const auto map = corridor_with_a_room_seen_through_a_door();
  const Plan home = plan_path_to(map, Pose2{18, 1.5, 0}, Point(2, 1.5), options());
  ASSERT_TRUE(home.ok) << home.error;
  ASSERT_NE(home.best_candidate(), nullptr);
  EXPECT_NEAR(home.best_candidate()->path_length_m, 16.0, 1e-2);
  const Plan room = plan_path_to(map, Pose2{18, 1.5, 0}, Point(16, 5.5), options());
  ASSERT_TRUE(room.ok);
  EXPECT_EQ(room.best_candidate(), nullptr);  // behind the 0.5 m neck
}

// The corridor with the room seen through its door, the door's west side
// moved to x = door_west_x (the neck stays narrower than the robot for x > 14.86).
mapping::TypedMultiPolygon corridor_with_a_room_seen_through_a_door_at(double door_west_x) {
  return {typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(20, 0), Point(20, 3), Point(15.5, 3), Point(15.5, 4), Point(18, 4), Point(18, 7),
       Point(14, 7), Point(14, 4), Point(door_west_x, 4), Point(door_west_x, 3), Point(0, 3)},
      {E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kFrontier,
       E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}})};
}

void expect_same_candidates(const Plan& a, const Plan& b) {
  ASSERT_TRUE(a.ok && b.ok) << a.error << b.error;
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (std::size_t i = 0; i < a.candidates.size(); ++i) {
    EXPECT_TRUE(boost::geometry::equals(a.candidates[i].position, b.candidates[i].position)) << i;
    EXPECT_EQ(a.candidates[i].approach, b.candidates[i].approach) << i;
    EXPECT_EQ(a.candidates[i].reachable, b.candidates[i].reachable) << i;
  }
  EXPECT_EQ(a.best, b.best);
  EXPECT_EQ(a.stats.approach_candidates, b.stats.approach_candidates);
}

// The approach points' tries are kept from one plan to the next while the
// edges near their frontier point stay the same, and searched afresh when
// those change: plans are the same with the cache and without.
TEST(PlanCache, ApproachTriesAreKeptWhileTheFrontiersSurroundingsStayTheSame) {
  PlanCache cache;
  const Pose2 robot{2, 1.5, 0};
  const auto door = corridor_with_a_room_seen_through_a_door_at(15.0);
  const Plan first = plan_exploration(door, robot, {}, options(), nullptr, nullptr, &cache);
  expect_same_candidates(first, plan_exploration(door, robot, {}, options()));
  ASSERT_GE(first.stats.approach_candidates, 1);
  const auto searched = cache.approaches.counters().searched;
  EXPECT_GE(searched, 1);
  EXPECT_EQ(cache.approaches.counters().kept, 0);

  // The same map again (the robot moved on): every search answered from the tries.
  const Pose2 moved{4, 1.5, 0};
  expect_same_candidates(plan_exploration(door, moved, {}, options(), nullptr, nullptr, &cache),
                         plan_exploration(door, moved, {}, options()));
  EXPECT_EQ(cache.approaches.counters().kept, searched);
  EXPECT_EQ(cache.approaches.counters().searched, searched);

  // The door's side moved (still too narrow for the robot): the walls near
  // the room's frontier changed, so it is searched again.
  const auto narrower = corridor_with_a_room_seen_through_a_door_at(15.1);
  expect_same_candidates(plan_exploration(narrower, moved, {}, options(), nullptr, nullptr, &cache),
                         plan_exploration(narrower, moved, {}, options()));
  EXPECT_GT(cache.approaches.counters().searched, searched);
}

// The plan cache keeps one visibility cache per clearance, the last three
// asked for: the normal and the tight plans of a mission and the narrower
// disk of the narrow-gap test do not evict each other's, a fourth clearance
// evicts the one used longest ago, and the counters of an evicted one stay
// in the sum.
TEST(PlanCache, OneVisibilityCachePerClearanceTheLastThreeKept) {
  PlanCache cache;
  PlannerOptions o = options();
  o.strategy = GoalStrategy::kTour;
  CSpaceOptions normal = o.cspace, tight = o.cspace, narrow = o.cspace, wide = o.cspace;
  tight.clearance_margin_m = 0.0;
  narrow.clearance_margin_m = 0.0;
  narrow.robot_radius_m -= 0.05;
  wide.clearance_margin_m = normal.clearance_margin_m + 0.3;
  VisibilityCache* const first = &cache.visibility(normal);
  EXPECT_NE(&cache.visibility(tight), first);
  EXPECT_EQ(&cache.visibility(normal), first);
  CSpaceOptions same_clearance = normal;
  same_clearance.points_per_circle = 32;  // not what the slot is chosen by
  EXPECT_EQ(&cache.visibility(same_clearance), first);

  // Through the planner: the tour builds its graph through the cache. The
  // tight and a third clearance after it: the normal slot keeps what it built.
  const Plan plan = plan_exploration(corridor_with_windows(), Pose2{1, 1.5, 0}, {}, o, nullptr, nullptr, &cache);
  ASSERT_TRUE(plan.ok) << plan.error;
  const auto builds = cache.visibility_counters().builds;
  EXPECT_EQ(builds, 1);
  cache.visibility(tight);
  EXPECT_EQ(cache.visibility(narrow).counters().builds, 0);
  EXPECT_EQ(cache.visibility(normal).counters().builds, 1);
  // A fourth clearance evicts the one used longest ago (now the tight one);
  // its counters stay in the sum.
  cache.visibility(wide);
  EXPECT_EQ(cache.visibility_counters().builds, builds);
  EXPECT_EQ(cache.visibility(normal).counters().builds, 1);
}

// The narrow-gap test of a plan with no goal builds the narrower disk's
// path graph through the plan cache: the next plan on the same map keeps its
// segment tests (each such plan tested the whole graph afresh before, 20 ms
// of a 50 ms tight plan on campus), and the plans are those without the cache.
TEST(PlanCache, TheNarrowGapTestKeepsItsPathGraphForTheNextPlan) {
  PlanCache cache;
  const PlannerOptions o = narrow_gap_options(0.0);
  CSpaceOptions narrower = o.cspace;  // the narrow-gap test's disk
  narrower.robot_radius_m -= o.narrow_gap_tolerance_m;
  const auto map = a_room_off_a_hall(0.5);
  const Pose2 robot{2, 2, 0};
  const Plan first = plan_exploration(map, robot, {}, o, nullptr, nullptr, &cache);
  expect_same_candidates(first, plan_exploration(map, robot, {}, o));
  ASSERT_NE(first.best_candidate(), nullptr);
  ASSERT_TRUE(first.best_candidate()->gap_mouth);  // the narrow-gap test ran
  const auto built = cache.visibility(narrower).counters();
  EXPECT_EQ(built.builds, 1);
  EXPECT_EQ(built.kept, 0);
  EXPECT_GE(built.new_pairs, 1);

  // The robot moved along the hall: the reflex nodes' tests are kept.
  const Pose2 moved{3, 2, 0};
  expect_same_candidates(plan_exploration(map, moved, {}, o, nullptr, nullptr, &cache),
                         plan_exploration(map, moved, {}, o));
  const auto again = cache.visibility(narrower).counters();
  EXPECT_EQ(again.builds, 2);
  EXPECT_GE(again.kept, 1);
  EXPECT_EQ(again.rebuilt, built.rebuilt);  // not built afresh (the first build is)
}

}  // namespace
}  // namespace pex::planning
