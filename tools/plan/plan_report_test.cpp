#include "plan_report.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "planning/test_maps.hpp"

using namespace pex::planning;
using namespace pex::planning::testing;

namespace {

// A 6 x 3 m room whose right side is a frontier; the robot at the left.
struct Fixture {
  TypedMultiPolygon map{typed_polygon(
      rectangle(0, 0, 6, 3, {EdgeType::kObstacle, EdgeType::kFrontier, EdgeType::kObstacle, EdgeType::kObstacle}))};
  pex::geometry::Pose2 robot{1.0, 1.5, 0.0};
  PlannerOptions options;
  ConfigurationSpace cspace;
  Plan plan;
  pex::polygon_map_t msg{};
  pex::pose_t pose{};
  Fixture() {
    options.cspace.robot_radius_m = 0.3;
    cspace.build(map, options.cspace);
    plan = plan_exploration(map, robot, {}, options);
    msg.utime = 7;
    msg.vertex_count = 4;
    pose.x = robot.x_m;
    pose.y = robot.y_m;
  }
};

// A plan on `map` from `robot` with the fixture's options, its C-space and
// what pex-plan says of it.
struct Described {
  Plan plan;
  ConfigurationSpace cspace;
  std::string text;
};
Described describe_plan(Fixture& f, const TypedMultiPolygon& map, const pex::geometry::Pose2& robot) {
  Described d;
  d.plan = plan_exploration(map, robot, {}, f.options);
  d.cspace.build(map, f.options.cspace);
  f.pose.x = robot.x_m;
  f.pose.y = robot.y_m;
  d.text = pex::plan_tool::describe(f.msg, f.pose, d.cspace, d.plan);
  return d;
}

}  // namespace

TEST(PlanReport, DescribesPiecesCandidatesAndTheBestOne) {
  Fixture f;
  ASSERT_TRUE(f.plan.ok) << f.plan.error;
  ASSERT_GE(f.plan.best, 0);
  const std::string text = pex::plan_tool::describe(f.msg, f.pose, f.cspace, f.plan);
  EXPECT_NE(text.find("C-space: 1 pieces"), std::string::npos) << text;
  EXPECT_NE(text.find("(the robot's)"), std::string::npos) << text;
  EXPECT_NE(text.find("<- best"), std::string::npos) << text;
  // Every candidate has a line with its path or "no path".
  std::size_t lines = 0;
  for (std::size_t at = text.find("frontier ("); at != std::string::npos; at = text.find("frontier (", at + 1)) ++lines;
  EXPECT_EQ(lines, f.plan.candidates.size());
  // Greedy searches paths only up to its goal: the others say so, no "inf m".
  EXPECT_EQ(text.find("inf"), std::string::npos) << text;
  std::size_t unsearched = 0;
  for (const auto& c : f.plan.candidates) unsearched += c.reachable && c.path.empty() ? 1 : 0;
  std::size_t said = 0;
  for (std::size_t at = text.find("not searched"); at != std::string::npos; at = text.find("not searched", at + 1)) ++said;
  EXPECT_EQ(said, unsearched);
}

TEST(PlanReport, ACandidateGreedyDidNotSearchSaysSo) {
  // A 20 m corridor, frontiers at both ends, the robot near the left one:
  // greedy stops at it and leaves the right one reachable, not searched.
  Fixture f;
  const TypedMultiPolygon map{typed_polygon(
      rectangle(0, 0, 20, 3, {EdgeType::kObstacle, EdgeType::kFrontier, EdgeType::kObstacle, EdgeType::kFrontier}))};
  const auto [plan, cspace, text] = describe_plan(f, map, {2.0, 1.5, 0.0});
  ASSERT_EQ(plan.candidates.size(), 2u);
  EXPECT_NE(text.find("<- best"), std::string::npos) << text;
  EXPECT_NE(text.find("reachable, path not searched"), std::string::npos) << text;
  EXPECT_EQ(text.find("inf"), std::string::npos) << text;
}

TEST(PlanReport, ACandidateInAnotherPieceSaysWhichPiece) {
  Fixture f;
  f.options.approach_range_m = 0.0;
  const TypedMultiPolygon map = a_room_cut_off_behind_a_slit();
  const auto [plan, cspace, text] = describe_plan(f, map, {1.0, 1.0, 0.0});
  ASSERT_EQ(plan.candidates.size(), 1u);
  const int piece = cspace.piece_of(plan.candidates[0].position);
  ASSERT_GE(piece, 0);
  EXPECT_NE(piece, cspace.piece_of(Point(1.0, 1.0)));
  EXPECT_NE(text.find("no path: in C-space piece " + std::to_string(piece) + ", not the robot's"), std::string::npos)
      << text;
}

// A frontier no C-space point sees (a sliver behind the corridor's wall) is
// listed with where it is, as pockets and enclosed ones are: a mission that
// ended DONE with "N behind walls" is traced from these lines.
TEST(PlanReport, AFrontierOutOfViewIsListedWithWhereItIs) {
  Fixture f;
  const TypedMultiPolygon map = {
      typed_polygon(rectangle(0, 0, 20, 3)),
      typed_polygon(rectangle(5, 3.05, 9, 3.15,
                              {EdgeType::kObstacle, EdgeType::kFrontier, EdgeType::kFrontier, EdgeType::kFrontier}))};
  const auto [plan, cspace, text] = describe_plan(f, map, {2.0, 1.5, 0.0});
  ASSERT_EQ(plan.out_of_view_frontier_points.size(), 1u);
  const auto& p = plan.out_of_view_frontier_points[0];
  char line[96];
  std::snprintf(line, sizeof line, "frontier (%.2f, %.2f): out of view", p.x(), p.y());
  EXPECT_NE(text.find(line), std::string::npos) << text;
}

TEST(PlanReport, AFailedPlanSaysWhy) {
  Fixture f;
  Plan failed;
  failed.error = "robot pose is not finite";
  const std::string text = pex::plan_tool::describe(f.msg, f.pose, f.cspace, failed);
  EXPECT_NE(text.find("plan failed: robot pose is not finite"), std::string::npos) << text;
}

TEST(PlanReport, SvgDrawsEdgesCandidatesAndThePath) {
  Fixture f;
  const std::string svg = pex::plan_tool::to_svg(f.map, f.robot, f.cspace, f.plan);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("#ff8800"), std::string::npos) << "no frontier edge drawn";
  EXPECT_NE(svg.find("<polyline"), std::string::npos) << "no path drawn";
  // A long ring is written whole (no fixed-size buffer cuts it).
  TypedMultiPolygon round{typed_polygon(RingSpec{[] {
    std::vector<Point> pts;
    for (int i = 0; i < 400; ++i) pts.emplace_back(3 + 2 * std::cos(i * 0.0157), 3 + 2 * std::sin(i * 0.0157));
    return pts;
  }(), {}})};
  const std::string big = pex::plan_tool::to_svg(round, f.robot, f.cspace, f.plan);
  const auto path_start = big.find("<path d=\"");
  ASSERT_NE(path_start, std::string::npos);
  EXPECT_NE(big.find("Z \" fill", path_start), std::string::npos);
}

TEST(PlanReport, TheBlacklistIsTheGoalsTheStateListsAsVisitedOrGivenUp) {
  pex::explore_state_t state{};
  state.frontier_x = {1.0, 2.0, 3.0, 4.0};
  state.frontier_y = {-1.0, -2.0, -3.0, -4.0};
  state.frontier_reason = {pex::explore_state_t::FRONTIER_VISITED, pex::explore_state_t::FRONTIER_NO_PATH,
                           pex::explore_state_t::FRONTIER_GIVEN_UP, pex::explore_state_t::FRONTIER_REACHABLE};
  state.nfrontiers = 4;
  auto blacklist = pex::plan_tool::blacklist_of(state);
  ASSERT_EQ(blacklist.size(), 2u);
  EXPECT_EQ(blacklist[0].x(), 1.0);
  EXPECT_EQ(blacklist[1].y(), -3.0);
  state.frontier_reason.resize(2);  // a malformed message: the arrays disagree
  blacklist = pex::plan_tool::blacklist_of(state);
  ASSERT_EQ(blacklist.size(), 1u);
  EXPECT_EQ(blacklist[0].x(), 1.0);
}

