#include "evaluation/exploration_metrics.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace pex::evaluation {
namespace {

namespace bg = boost::geometry;
using mapping::EdgeType;
using mapping::MultiPolygon;
using mapping::Point;
using mapping::Polygon;

constexpr double kR = 0.25;
// Area of a 90-degree room corner that the robot's disk cannot reach.
const double kCornerLoss = kR * kR * (1.0 - std::numbers::pi / 4.0);

sim::World world_from(const std::string& text) {
  auto parsed = sim::parse_world(text, "test");
  EXPECT_TRUE(std::holds_alternative<sim::World>(parsed)) << std::get<sim::WorldError>(parsed).message;
  return std::get<sim::World>(parsed);
}

MultiPolygon polygon(const std::string& wkt) {
  Polygon p;
  bg::read_wkt(wkt, p);
  bg::correct(p);
  return {p};
}

mapping::TypedMultiPolygon typed(const MultiPolygon& geometry, EdgeType type = EdgeType::kObstacle) {
  return mapping::with_uniform_type(geometry, type);
}

// A 6 x 4 m room of line walls.
const char* kRoom = "START 3 2 0\nLINESTRING(0 0, 6 0, 6 4, 0 4, 0 0)\n";

TEST(ReachableFreeSpace, RoomLosesOnlyItsCorners) {
  const auto world = world_from(kRoom);
  const auto cfree = configuration_free_component(world, kR, world.start);
  EXPECT_NEAR(bg::area(cfree), (6 - 2 * kR) * (4 - 2 * kR), 1e-9);  // axis-parallel: exact
  const auto reachable = reachable_free_space(world, kR, world.start);
  ASSERT_EQ(reachable.size(), 1u);
  EXPECT_TRUE(bg::is_valid(reachable));
  // The disk polygon is inscribed in the circle: 1e-3 m2 covers that.
  EXPECT_NEAR(bg::area(reachable), 24.0 - 4 * kCornerLoss, 1e-3);
  EXPECT_TRUE(bg::covered_by(Point(0.01, 2.0), reachable));  // against a wall
  EXPECT_FALSE(bg::covered_by(Point(0.02, 0.02), reachable));  // in a corner
}

TEST(ReachableFreeSpace, RoomBehindADoorNarrowerThanTheRobotIsNotReachable) {
  // Two 6 x 4 rooms; the wall between them at x = 6 has a door at y 1.8..door_top.
  auto two_rooms = [](double door_m) {
    std::ostringstream text;
    text << "START 3 2 0\nLINESTRING(0 0, 12 0, 12 4, 0 4, 0 0)\nLINESTRING(6 0, 6 1.8)\nLINESTRING(6 "
         << 1.8 + door_m << ", 6 4)\n";
    return world_from(text.str());
  };
  const auto narrow = two_rooms(0.4);  // < 2 r = 0.5
  const auto behind_narrow = reachable_free_space(narrow, kR, narrow.start);
  EXPECT_TRUE(bg::covered_by(Point(3, 2), behind_narrow));
  EXPECT_FALSE(bg::covered_by(Point(9, 2), behind_narrow));
  // The left room, less its corners, plus the bit of the doorway the disk
  // sweeps from the left (it reaches 0.1 m past x = 6).
  EXPECT_GT(bg::area(behind_narrow), 24.0 - 4 * kCornerLoss - 1e-3);
  EXPECT_LT(bg::area(behind_narrow), 24.0 + 0.1);

  const auto wide = two_rooms(0.6);
  const auto both = reachable_free_space(wide, kR, wide.start);
  EXPECT_TRUE(bg::covered_by(Point(9, 2), both));
  // Both rooms, eight corners lost, the door jambs' free ends lose nothing.
  EXPECT_NEAR(bg::area(both), 48.0 - 8 * kCornerLoss, 2e-3);
}

TEST(ReachableFreeSpace, StartInCollisionGivesNothing) {
  const auto world = world_from("START 0.1 2 0\nLINESTRING(0 0, 6 0, 6 4, 0 4, 0 0)\n");
  EXPECT_TRUE(reachable_free_space(world, kR, world.start).empty());
  EXPECT_TRUE(reachable_free_space(world, 0.0, {3, 2, 0}).empty());
}

TEST(ReachableFreeSpace, OpenOutsideIsClippedToTheWallsBox) {
  // A solid building and two short walls that span the box 0..10; the robot
  // starts outside the building and may pass round outside the box.
  const auto world = world_from(
      "START 1 5 0\nPOLYGON((4 4, 6 4, 6 6, 4 6, 4 4))\nLINESTRING(0 0, 1 0)\nLINESTRING(9 10, 10 10)\n");
  const auto reachable = reachable_free_space(world, kR, world.start);
  EXPECT_NEAR(bg::area(reachable), 100.0 - 4.0, 1e-9);  // a building's outer corners lose nothing
  EXPECT_FALSE(bg::covered_by(Point(5, 5), reachable));    // inside the building
}

TEST(ReachableFreeSpace, ShippedTwoRoomsMatchesItsStatedFreeAreaLessCorners) {
  const std::string path = std::string(PEX_SOURCE_DIR) + "/worlds/two_rooms.wkt";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  const auto world = world_from(text.str());
  const auto reachable = reachable_free_space(world, kR, world.start);
  // 82.66 m2 of free area (the file's comment) less eight room corners: the
  // box and the pillar stand free (their corners are outer corners).
  EXPECT_NEAR(bg::area(reachable), 82.66 - 8 * kCornerLoss, 2e-3);

  // Every point within r of the C-free component is in the result, and no
  // other (away from a 1 mm band where the polygonal disk may differ).
  const auto cfree = configuration_free_component(world, kR, world.start);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(world.min_x, world.max_x), uy(world.min_y, world.max_y);
  int disagree = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const Point p(ux(rng), uy(rng));
    const double d = bg::distance(p, cfree);
    if (std::abs(d - kR) < 1e-3) continue;
    ++checked;
    if ((d <= kR) != bg::covered_by(p, reachable)) ++disagree;
  }
  EXPECT_GT(checked, 19000);
  EXPECT_EQ(disagree, 0);
}

// Every shipped world: a valid reachable space holding START, and the
// Minkowski sum checked on random points.
TEST(ReachableFreeSpace, EveryShippedWorld) {
  int worlds = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(PEX_SOURCE_DIR) + "/worlds")) {
    if (entry.path().extension() != ".wkt") continue;
    ++worlds;
    SCOPED_TRACE(entry.path().filename().string());
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    const auto world = world_from(text.str());
    const auto cfree = configuration_free_component(world, kR, world.start);
    const auto reachable = reachable_free_space(world, kR, world.start);
    ASSERT_FALSE(reachable.empty());
    EXPECT_TRUE(bg::is_valid(reachable));
    EXPECT_TRUE(bg::covered_by(Point(world.start.x_m, world.start.y_m), cfree));
    EXPECT_LE(bg::area(reachable), (world.max_x - world.min_x) * (world.max_y - world.min_y));
    EXPECT_GT(bg::area(reachable), bg::area(cfree));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> ux(world.min_x, world.max_x), uy(world.min_y, world.max_y);
    int disagree = 0;
    for (int i = 0; i < 2000; ++i) {
      const Point p(ux(rng), uy(rng));
      const double d = bg::distance(p, cfree);
      if (std::abs(d - kR) >= 1e-3 && (d <= kR) != bg::covered_by(p, reachable)) ++disagree;
    }
    EXPECT_EQ(disagree, 0);
  }
  EXPECT_GE(worlds, 5);
}

TEST(MapScores, MapEqualToTheReachableSpaceScoresOne) {
  const auto world = world_from(kRoom);
  const auto reachable = reachable_free_space(world, kR, world.start);
  EXPECT_NEAR(coverage(reachable, reachable), 1.0, 1e-9);
  EXPECT_NEAR(iou(reachable, reachable), 1.0, 1e-9);

  // The same map given in the start frame (pose 3, 2, 90 deg): score_map
  // moves it to the world with the start pose.
  const geometry::Pose2 start{3.0, 2.0, std::numbers::pi / 2};
  MultiPolygon in_start_frame = reachable;
  for (auto& poly : in_start_frame)
    for (auto& p : poly.outer()) {
      const double dx = p.x() - start.x_m, dy = p.y() - start.y_m;
      p = Point(dy, -dx);  // rotate by -90 deg
    }
  const auto back = to_world(in_start_frame, start);
  EXPECT_NEAR(back.front().outer().front().x(), reachable.front().outer().front().x(), 1e-12);
  const WallIndex walls(world.walls);
  const auto score = score_map(typed(in_start_frame), start, reachable, walls, 0.1);
  EXPECT_NEAR(score.coverage, 1.0, 1e-9);
  EXPECT_NEAR(score.iou, 1.0, 1e-9);
  EXPECT_NEAR(score.explored_m2, bg::area(reachable), 1e-9);
  // Left in the start frame (identity), it hardly overlaps.
  EXPECT_LT(score_map(typed(in_start_frame), {}, reachable, walls, 0.1).iou, 0.5);
}

TEST(MapScores, HalfMapCoversHalf) {
  const auto world = world_from(kRoom);
  const auto reachable = reachable_free_space(world, kR, world.start);
  const auto left_half = polygon("POLYGON((0 0, 3 0, 3 4, 0 4, 0 0))");
  MultiPolygon half;
  bg::intersection(reachable, left_half, half);
  EXPECT_NEAR(coverage(half, reachable), 0.5, 1e-9);  // the room is symmetric
  EXPECT_NEAR(iou(half, reachable), 0.5, 1e-9);

  // Free space mapped beyond the walls counts against IoU, not coverage.
  const auto beyond = polygon("POLYGON((-2 0, 0 0, 0 4, -2 4, -2 0))");
  MultiPolygon overreach;
  bg::union_(half, beyond, overreach);
  EXPECT_NEAR(coverage(overreach, reachable), 0.5, 1e-9);
  const double a = bg::area(reachable);
  EXPECT_NEAR(iou(overreach, reachable), 0.5 * a / (a + 8.0), 1e-9);

  EXPECT_NEAR(coverage(MultiPolygon{}, reachable), 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(coverage(half, MultiPolygon{})));
  EXPECT_TRUE(std::isnan(iou(MultiPolygon{}, MultiPolygon{})));
}

TEST(MapScores, ObstacleBandCreditCountsTheStripBehindObstacleEdgesOnly) {
  const auto world = world_from(kRoom);
  const auto reachable = reachable_free_space(world, kR, world.start);
  const WallIndex walls(world.walls);
  // A map whose walls stop 5 cm short of the real ones (the obstacle band).
  const auto inset = polygon("POLYGON((0.05 0.05, 5.95 0.05, 5.95 3.95, 0.05 3.95, 0.05 0.05))");
  const auto raw = score_map(typed(inset), {}, reachable, walls, 0.1);
  EXPECT_LT(raw.coverage, 0.97);
  const auto credited = score_map(typed(inset), {}, reachable, walls, 0.1, 0.1);
  EXPECT_NEAR(credited.coverage, 1.0, 1e-9);
  EXPECT_GT(credited.iou, 0.999);  // the map's corners beyond the robot's reach still count
  EXPECT_LT(credited.iou, 1.0);
  EXPECT_DOUBLE_EQ(credited.explored_m2, raw.explored_m2);
  // Frontier edges earn nothing.
  const auto frontier = score_map(typed(inset, EdgeType::kFrontier), {}, reachable, walls, 0.1, 0.1);
  EXPECT_DOUBLE_EQ(frontier.coverage, raw.coverage);
}

TEST(MapScores, CreditNearWorldWallsDoesNotHideAGhostWall) {
  const auto world = world_from(kRoom);
  const auto reachable = reachable_free_space(world, kR, world.start);
  const WallIndex walls(world.walls);
  // The inset room with a ghost wall across its middle: a 0.2 m strip of
  // obstacle edges where the world has floor.
  const auto ghost = polygon(
      "POLYGON((0.05 0.05, 5.95 0.05, 5.95 3.95, 0.05 3.95, 0.05 0.05), (2.9 1, 2.9 3, 3.1 3, 3.1 1, 2.9 1))");
  const auto near_map = score_map(typed(ghost), {}, reachable, walls, 0.1, 0.1);
  EXPECT_NEAR(near_map.coverage, 1.0, 1e-9);  // the strip lies within 0.1 m of its own edges
  const auto near_walls = score_map(typed(ghost), {}, reachable, walls, 0.1, 0.1, CreditNear::kWorldWalls);
  EXPECT_NEAR(near_walls.coverage, 1.0 - 0.4 / bg::area(reachable), 1e-6);
  // Without the ghost the two credits agree: the inset map's edges run along the walls.
  const auto inset = polygon("POLYGON((0.05 0.05, 5.95 0.05, 5.95 3.95, 0.05 3.95, 0.05 0.05))");
  EXPECT_NEAR(score_map(typed(inset), {}, reachable, walls, 0.1, 0.1, CreditNear::kWorldWalls).coverage, 1.0, 1e-9);
}

TEST(ObstacleOnWall, ShareOfObstacleLengthNearWalls) {
  const auto world = world_from(kRoom);
  // The left 3 x 4 m of the room: 10 m of its edges on walls, 4 m (x = 3)
  // not, but for its ends within 0.1 m of the walls at y = 0 and y = 4.
  const auto left = polygon("POLYGON((0 0, 3 0, 3 4, 0 4, 0 0))");
  EXPECT_NEAR(obstacle_on_wall(typed(left), world, 0.1), 10.2 / 14.0, 1e-12);
  EXPECT_TRUE(std::isnan(obstacle_on_wall(typed(left, EdgeType::kFrontier), world, 0.1)));
  // Walls seen 5 cm inside the room: on the wall with 10 cm tolerance, not with 3 cm.
  const auto inset = polygon("POLYGON((0.05 0.05, 5.95 0.05, 5.95 3.95, 0.05 3.95, 0.05 0.05))");
  EXPECT_NEAR(obstacle_on_wall(typed(inset), world, 0.1), 1.0, 1e-12);
  EXPECT_NEAR(obstacle_on_wall(typed(inset), world, 0.03), 0.0, 1e-12);
  // Only obstacle edges count: type the x = 3 edge frontier.
  auto mixed = typed(left);
  const auto& ring = mixed.front().geometry.outer();
  for (std::size_t i = 0; i + 1 < ring.size(); ++i)
    if (ring[i].x() == 3.0 && ring[i + 1].x() == 3.0) mixed.front().edge_types[0][i] = EdgeType::kFrontier;
  EXPECT_NEAR(obstacle_on_wall(mixed, world, 0.1), 1.0, 1e-12);
}

TEST(ObstacleOnWall, ExactLengthAgreesWithFineSampling) {
  // Walls at odd angles and short pieces; random edges across them.
  const auto world = world_from(
      "LINESTRING(0 0, 4 1, 5 4, 2 5)\nLINESTRING(1 2, 1.3 2.1)\nPOLYGON((2 2, 3 2.2, 2.6 3, 2 2))\n");
  const WallIndex walls(world.walls);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 5.5);
  for (int i = 0; i < 300; ++i) {
    const Point a(u(rng), u(rng));
    const Point b(a.x() + 0.3 * (u(rng) - 2.5), a.y() + 0.3 * (u(rng) - 2.5));
    const double tol = 0.05 + 0.002 * (i % 100);
    const double exact = walls.length_near_walls(a, b, tol);
    const int n = 20000;
    const double length = bg::distance(a, b);
    double sampled = 0.0;
    for (int k = 0; k < n; ++k) {
      const double s = (k + 0.5) / n;
      if (walls.distance(Point(a.x() + s * (b.x() - a.x()), a.y() + s * (b.y() - a.y()))) <= tol)
        sampled += length / n;
    }
    ASSERT_NEAR(exact, sampled, 4 * length / n + 1e-12) << "edge " << i;
  }
}

}  // namespace
}  // namespace pex::evaluation
