#include "planning/guard_marks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <boost/geometry.hpp>

#include "planning/mission.hpp"
#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

namespace bg = boost::geometry;
using mapping::EdgeType;
using mapping::Point;
using E = EdgeType;

// A line of returns across the way at x (robot frame), from y0 to y1.
std::vector<Point> line_across(double x, double y0, double y1) {
  std::vector<Point> points;
  for (double y = y0; y <= y1 + 1e-9; y += 0.02) points.emplace_back(x, y);
  return points;
}

bool covers(const mapping::TypedMultiPolygon& area, const Point& p) {
  for (const auto& polygon : area)
    if (bg::covered_by(p, polygon.geometry)) return true;
  return false;
}

TEST(GuardMarks, TheHoldingPointsAreThePatchInTheWayNotTheWallBehindNorWhatIsBeside) {
  constexpr double kBody = 0.25;
  std::vector<Point> scan = line_across(0.30, -0.05, 0.05);  // a pane seen head-on, 5 cm before the body
  for (const Point& p : line_across(2.0, -1.0, 1.0)) scan.push_back(p);  // the wall behind it
  scan.emplace_back(0.0, 0.6);  // a wall beside the robot
  const GuardMarkOptions options;
  const auto holding = holding_points(scan, 0.0, kBody, options);
  ASSERT_EQ(holding.size(), 6u);
  for (const Point& p : holding) EXPECT_NEAR(p.x(), 0.30, 1e-9);
  // On an arc turning left the pane still holds the body, and so does a
  // return the left side would sweep into.
  scan.emplace_back(0.22, 0.22);
  const auto turning = holding_points(scan, 1.0, kBody, options);
  EXPECT_TRUE(std::any_of(turning.begin(), turning.end(), [](const Point& p) { return p.y() > 0.21; }));
  EXPECT_FALSE(std::any_of(holding.begin(), holding.end(), [](const Point& p) { return p.y() > 0.21; }));
  // Nothing within reach: nothing holds the robot.
  EXPECT_TRUE(holding_points(line_across(2.0, -1.0, 1.0), 0.0, kBody, options).empty());
  EXPECT_TRUE(holding_points({}, 0.0, kBody, options).empty());
}

TEST(GuardMarks, AMarkIsTheHoldInTheMapFrameKeptForItsLifetimeAndNoMoreThanMax) {
  GuardMarkOptions options;
  options.lifetime_s = 10.0;
  options.max_marks = 2;
  GuardMarks marks(options);
  EXPECT_EQ(marks.with_keep_out(nullptr), nullptr);
  EXPECT_FALSE(marks.add({}, {}, 0));  // nothing in the way: no mark
  // The robot at (3, 1) facing +y: a return 0.3 m ahead is (3, 1.3) in the map.
  const geometry::Pose2 robot{3.0, 1.0, M_PI / 2};
  const auto pane = line_across(0.30, -0.05, 0.05);
  ASSERT_TRUE(marks.add(pane, robot, 1'000'000));
  const auto first = marks.with_keep_out(nullptr);
  ASSERT_NE(first, nullptr);
  EXPECT_TRUE(covers(*first, Point(3.0, 1.3)));
  EXPECT_TRUE(covers(*first, Point(3.04, 1.31)));
  EXPECT_FALSE(covers(*first, Point(3.0, 1.4)));
  EXPECT_FALSE(covers(*first, Point(3.0, 1.0)));  // not where the robot stands
  EXPECT_EQ(marks.with_keep_out(nullptr), first);  // unchanged: the same pointer (caches key on it)

  // With the operator's keep-out: both in one.
  auto keep_out = std::make_shared<const mapping::TypedMultiPolygon>(
      mapping::TypedMultiPolygon{testing::typed_polygon(testing::rectangle(10, 10, 11, 11))});
  const auto both = marks.with_keep_out(keep_out);
  ASSERT_NE(both, nullptr);
  EXPECT_NE(both, first);
  EXPECT_TRUE(covers(*both, Point(3.0, 1.3)));
  EXPECT_TRUE(covers(*both, Point(10.5, 10.5)));

  ASSERT_TRUE(marks.add(pane, {5.0, 1.0, M_PI / 2}, 2'000'000));
  ASSERT_TRUE(marks.add(pane, {7.0, 1.0, M_PI / 2}, 3'000'000));
  EXPECT_EQ(marks.size(), 2u);  // the oldest went
  const auto two = marks.with_keep_out(nullptr);
  EXPECT_FALSE(covers(*two, Point(3.0, 1.3)));
  EXPECT_TRUE(covers(*two, Point(5.0, 1.3)));
  EXPECT_TRUE(covers(*two, Point(7.0, 1.3)));

  EXPECT_EQ(marks.expire(12'000'000), 0);  // the mark of 2 s is 10 s old: kept
  EXPECT_EQ(marks.expire(12'000'001), 1);  // older: gone
  EXPECT_EQ(marks.size(), 1u);
  EXPECT_TRUE(covers(*marks.with_keep_out(nullptr), Point(7.0, 1.3)));
  EXPECT_EQ(marks.expire(13'000'001), 1);
  EXPECT_EQ(marks.with_keep_out(nullptr), nullptr);

  options.lifetime_s = 0.0;  // off
  GuardMarks off(options);
  EXPECT_FALSE(off.add(pane, robot, 0));
}

// A restarted explorer takes its marks up from a checkpoint: the newest
// max_marks of them, with their times; a damaged checkpoint leaves the marks
// as they were; a mark from another clock's run (made "after" now) goes.
TEST(GuardMarks, TheMarksTakenUpFromACheckpointAreTheMarksThatWereKept) {
  GuardMarkOptions options;
  options.lifetime_s = 10.0;
  GuardMarks marks(options);
  EXPECT_EQ(marks.checkpoint(), "");  // none: nothing to keep
  const auto pane = line_across(0.30, -0.05, 0.05);
  ASSERT_TRUE(marks.add(pane, {3.0, 1.0, M_PI / 2}, 1'000'000));
  ASSERT_TRUE(marks.add(pane, {5.0, 1.0, M_PI / 2}, 2'000'000));
  ASSERT_TRUE(marks.add(pane, {7.0, 1.0, M_PI / 2}, 3'000'000));
  const std::string saved = marks.checkpoint();
  ASSERT_FALSE(saved.empty());

  GuardMarks all(options);
  ASSERT_EQ(all.restore(saved), "");
  ASSERT_EQ(all.size(), 3u);
  for (double x : {3.0, 5.0, 7.0}) {
    EXPECT_TRUE(covers(*all.with_keep_out(nullptr), Point(x, 1.3))) << x;
  }
  EXPECT_FALSE(covers(*all.with_keep_out(nullptr), Point(4.0, 1.3)));
  EXPECT_EQ(all.expire(11'000'001), 1);  // the times came along: the mark of 1 s is the one that goes
  EXPECT_FALSE(covers(*all.with_keep_out(nullptr), Point(3.0, 1.3)));

  options.max_marks = 2;
  GuardMarks fewer(options);
  ASSERT_EQ(fewer.restore(saved), "");
  EXPECT_EQ(fewer.size(), 2u);
  EXPECT_FALSE(covers(*fewer.with_keep_out(nullptr), Point(3.0, 1.3)));  // the oldest left out
  EXPECT_TRUE(covers(*fewer.with_keep_out(nullptr), Point(7.0, 1.3)));

  // Damaged: every byte flipped in turn, and cut short; refused, the marks kept.
  for (std::size_t i = 0; i < saved.size(); i += 7) {
    std::string bad = saved;
    bad[i] = static_cast<char>(bad[i] ^ 0x5a);
    EXPECT_NE(fewer.restore(bad), "") << i;
    EXPECT_EQ(fewer.size(), 2u);
  }
  EXPECT_NE(fewer.restore(saved.substr(0, saved.size() - 1)), "");
  EXPECT_NE(fewer.restore("not a checkpoint"), "");
  EXPECT_EQ(fewer.size(), 2u);

  // Taken up by a run whose clock started again (a rebooted robot): the
  // marks are from "the future" and go at the first expiry.
  GuardMarks rebooted(options);
  ASSERT_EQ(rebooted.restore(saved), "");
  EXPECT_EQ(rebooted.expire(500'000), 2);
  EXPECT_EQ(rebooted.with_keep_out(nullptr), nullptr);
}

// Two rooms, the wall between them at x = 4 .. 4.2: glass below y = 1.5,
// a door at 1.5 .. 2.5, plaster above. The map has the plaster only: the
// glass was seen through, so both rooms are one free area below y = 2.5.
// Room B's east side is a frontier.
mapping::TypedMultiPolygon map_with_the_glass_seen_through() {
  using testing::typed_polygon;
  return {typed_polygon({{Point(0, 0), Point(8.2, 0), Point(8.2, 4), Point(4.2, 4), Point(4.2, 2.5), Point(4, 2.5),
                          Point(4, 4), Point(0, 4)},
                         {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle,
                          E::kObstacle, E::kObstacle}})};
}

TEST(GuardMarks, APlanGoesRoundTheMarksThroughTheDoorAndDropsMarksThatShutTheRobotIn) {
  const Pose2 robot{2.0, 0.7, 0.0};
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map_with_the_glass_seen_through());
  request.pose = robot;
  request.options = testing::door_planner_options();
  // Without marks the path runs straight through the glass.
  const PlanResult unmarked = compute_plan(request);
  ASSERT_NE(unmarked.plan.best_candidate(), nullptr) << unmarked.plan.error;
  EXPECT_LT(testing::crossing_y(unmarked.plan.best_candidate()->path, 4.1), 1.5);

  // Held three times along the pane, facing it (+x) from 0.3 m: the marks
  // cover it, y = 0 .. 1.5 (the returns in robot frame at x = 0.3).
  GuardMarks marks;
  for (double y : {0.25, 0.75, 1.25})
    ASSERT_TRUE(marks.add(line_across(0.30, -0.25, 0.25), {3.7, y, 0.0}, 0));
  request.keep_out = marks.with_keep_out(nullptr);
  request.has_guard_marks = true;
  const PlanResult marked = compute_plan(request);
  const GoalCandidate* goal = marked.plan.best_candidate();
  ASSERT_NE(goal, nullptr) << marked.plan.error;
  EXPECT_FALSE(marked.guard_marks_dropped);
  EXPECT_GT(goal->position.x(), 4.2);
  EXPECT_GT(testing::crossing_y(goal->path, 4.1), 1.5 + 0.27);  // the door
  EXPECT_LT(testing::crossing_y(goal->path, 4.1), 2.5 - 0.27);

  // A mark across the door too (someone stood in it): the marks leave no
  // way, so the plan is made again without them.
  ASSERT_TRUE(marks.add(line_across(0.30, -0.5, 0.5), {3.7, 2.0, 0.0}, 0));
  request.keep_out = marks.with_keep_out(nullptr);
  const PlanResult shut = compute_plan(request);
  EXPECT_TRUE(shut.guard_marks_dropped);
  ASSERT_NE(shut.plan.best_candidate(), nullptr) << shut.plan.error;
  EXPECT_LT(testing::crossing_y(shut.plan.best_candidate()->path, 4.1), 1.5);
}

}  // namespace
}  // namespace pex::planning
