#include "make_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

namespace pex::make_world {
namespace {

struct Segment {
  double x0, y0, x1, y1;
};

// Distance along a ray to the nearest segment, or `no_return` when none.
double cast(const std::vector<Segment>& walls, double x, double y, double angle, double no_return) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  double best = no_return;
  for (const auto& s : walls) {
    const double ex = s.x1 - s.x0, ey = s.y1 - s.y0;
    const double den = dx * ey - dy * ex;
    if (std::abs(den) < 1e-12) continue;
    const double t = ((s.x0 - x) * ey - (s.y0 - y) * ex) / den;
    const double u = ((s.x0 - x) * dy - (s.y0 - y) * dx) / den;
    if (t > 0 && u >= 0 && u <= 1) best = std::min(best, t);
  }
  return best;
}

std::vector<Segment> box(double x0, double y0, double x1, double y1) {
  return {{x0, y0, x1, y0}, {x1, y0, x1, y1}, {x1, y1, x0, y1}, {x0, y1, x0, y0}};
}

// A 360° scanner, 0.5° steps, noise-free; 80 m means no return.
PosedScan scan_at(const std::vector<Segment>& walls, Pose2 pose) {
  PosedScan s;
  s.sensor = pose;
  s.angle_min_rad = -std::numbers::pi;
  s.angle_increment_rad = std::numbers::pi / 360.0;
  s.no_return_m = 80.0;
  for (int i = 0; i < 720; ++i) {
    s.ranges_m.push_back(
        static_cast<float>(cast(walls, pose.x_m, pose.y_m, pose.theta_rad + s.angle_min_rad + i * s.angle_increment_rad, 80.0)));
  }
  return s;
}

double distance_to(const std::vector<Segment>& walls, const Point& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& s : walls) {
    const double vx = s.x1 - s.x0, vy = s.y1 - s.y0;
    const double t = std::clamp(((p.x - s.x0) * vx + (p.y - s.y0) * vy) / (vx * vx + vy * vy), 0.0, 1.0);
    best = std::min(best, std::hypot(p.x - s.x0 - t * vx, p.y - s.y0 - t * vy));
  }
  return best;
}

bool region_at(const World& w, const OccupancyGrid& g, double x, double y) {
  return w.region[static_cast<std::size_t>(g.cell_y(y)) * g.width() + g.cell_x(x)] != 0;
}
bool reachable_at(const World& w, const OccupancyGrid& g, double x, double y) {
  return w.reachable[static_cast<std::size_t>(g.cell_y(y)) * g.width() + g.cell_x(x)] != 0;
}

World extract_ok(const OccupancyGrid& grid, const std::vector<Pose2>& trajectory, WorldOptions options = {}) {
  auto r = extract_world(grid, trajectory, options);
  if (auto* err = std::get_if<std::string>(&r)) {
    ADD_FAILURE() << *err;
    return {};
  }
  return std::get<World>(std::move(r));
}

TEST(Grid, OneBeamMissesAlongAndHitsAtItsEnd) {
  OccupancyGrid grid(0.0, 0.0, 40, 3, 0.05);
  PosedScan s;
  s.sensor = {0.025, 0.075, 0.0};
  s.angle_increment_rad = 0.01;
  s.no_return_m = 80.0;
  s.ranges_m = {1.0};  // ends at x = 1.025: cell 20
  GridOptions o;
  grid.integrate(s, o);
  for (int x = 0; x < 20; ++x) EXPECT_FLOAT_EQ(grid.log_odds(x, 1), static_cast<float>(o.miss_log_odds)) << x;
  EXPECT_FLOAT_EQ(grid.log_odds(20, 1), static_cast<float>(o.hit_log_odds));
  EXPECT_FLOAT_EQ(grid.log_odds(21, 1), 0.0f);
  EXPECT_FLOAT_EQ(grid.log_odds(5, 0), 0.0f);
  EXPECT_FLOAT_EQ(grid.log_odds(5, 2), 0.0f);
}

TEST(Grid, NoReturnAndTooLongBeams) {
  GridOptions o;
  o.max_range_m = 0.5;
  PosedScan s;
  s.sensor = {0.025, 0.075, 0.0};
  s.no_return_m = 80.0;
  s.ranges_m = {1.0f};
  OccupancyGrid grid(0.0, 0.0, 40, 3, 0.05);
  grid.integrate(s, o);  // longer than max_range_m: free up to 0.5 m, no hit
  for (int x = 0; x < 10; ++x) EXPECT_LT(grid.log_odds(x, 1), 0.0f) << x;
  for (int x = 11; x < 40; ++x) EXPECT_FLOAT_EQ(grid.log_odds(x, 1), 0.0f) << x;
  OccupancyGrid grid2(0.0, 0.0, 40, 3, 0.05);
  s.ranges_m = {80.0f};  // no return: dropped by default
  grid2.integrate(s, o);
  for (int x = 0; x < 40; ++x) EXPECT_FLOAT_EQ(grid2.log_odds(x, 1), 0.0f) << x;
  o.free_on_no_return = true;
  grid2.integrate(s, o);
  EXPECT_LT(grid2.log_odds(3, 1), 0.0f);
}

TEST(Rings, SimplifyKeepsCornersAndTolerance) {
  Ring square;
  for (int i = 0; i < 10; ++i) square.push_back({i * 0.1, 0.0});
  for (int i = 0; i < 10; ++i) square.push_back({1.0, i * 0.1});
  for (int i = 0; i < 10; ++i) square.push_back({1.0 - i * 0.1, 1.0});
  for (int i = 0; i < 10; ++i) square.push_back({0.0, 1.0 - i * 0.1});
  const Ring s = simplify_ring(square, 0.01);
  EXPECT_EQ(s.size(), 4u);
  EXPECT_NEAR(signed_area(s), 1.0, 1e-9);
  // A zig-zag of 2 cm stays within a 3 cm tolerance, not within 1 cm.
  Ring zig = square;
  for (std::size_t i = 1; i < 9; i += 2) zig[i].y = 0.02;
  EXPECT_EQ(simplify_ring(zig, 0.03).size(), 4u);
  EXPECT_GT(simplify_ring(zig, 0.01).size(), 4u);
}

// A 6 × 4 m room with a 0.6 m square pillar, seen from a few poses.
struct Room {
  std::vector<Segment> walls;
  std::vector<Pose2> poses;
};

// Off the grid's cell borders (the grid starts at a multiple of the cell
// size), as real walls are.
constexpr double kX = 0.013, kY = 0.021;

Room room_with_pillar() {
  Room r;
  r.walls = box(kX, kY, 6 + kX, 4 + kY);
  for (auto s : box(3.7 + kX, 1.7 + kY, 4.3 + kX, 2.3 + kY)) r.walls.push_back(s);
  r.poses = {{1.0, 1.0, 0.0}, {1.5, 3.0, 0.5}, {5.2, 3.2, 2.0}, {5.0, 0.8, -1.0}, {2.5, 2.0, 0.0}};
  return r;
}

OccupancyGrid grid_of(const Room& r, const GridOptions& o = {}) {
  std::vector<PosedScan> scans;
  for (const auto& p : r.poses) scans.push_back(scan_at(r.walls, p));
  return build_grid(scans, o);
}

TEST(World, RoomGivesWallsAtTheRightPlace) {
  const Room r = room_with_pillar();
  const OccupancyGrid grid = grid_of(r);
  const World w = extract_ok(grid, r.poses);
  // Every wall vertex lies on a real wall (within a cell), the boundary spans the room.
  for (const auto& p : w.boundary) EXPECT_LT(distance_to(r.walls, p), 0.06) << p.x << " " << p.y;
  // The free space ends in front of each wall by up to a cell, plus the
  // tolerance of the simplification at the corners.
  EXPECT_GT(w.min_x, kX - 0.01);
  EXPECT_LT(w.min_x, kX + 0.08);
  EXPECT_LT(w.max_x, 6.0 + kX + 0.01);
  EXPECT_GT(w.max_x, 6.0 + kX - 0.08);
  EXPECT_GT(w.min_y, kY - 0.01);
  EXPECT_LT(w.min_y, kY + 0.08);
  EXPECT_LT(w.max_y, 4.0 + kY + 0.01);
  EXPECT_GT(w.max_y, 4.0 + kY - 0.08);
  EXPECT_LE(w.boundary.size(), 12u);  // four straight walls: the cells' outline had ~800 points
  // The pillar is the one obstacle, at its place with its size (its hit cells
  // hold its faces: up to a cell larger on each side).
  ASSERT_EQ(w.obstacles.size(), 1u);
  EXPECT_GE(signed_area(w.obstacles[0]), 0.36 - 0.01);
  EXPECT_LE(signed_area(w.obstacles[0]), 0.7 * 0.7);
  for (const auto& p : w.obstacles[0]) EXPECT_LT(distance_to(r.walls, p), 0.06);
  // Free area: the room less the pillar; reachable: less a 0.25 m band. A
  // wall's face lies in its hit cell, so the free space ends up to one cell
  // (5 cm) short of it: at most a 5 cm band along every wall is missing.
  const double free_exact = 24.0 - 0.36, free_perimeter = 20.0 + 2.4;
  EXPECT_LE(w.free_area_m2, free_exact + 0.05);
  EXPECT_GE(w.free_area_m2, free_exact - 0.05 * free_perimeter);
  const double reach_exact = 5.5 * 3.5 - 1.1 * 1.1 + (4 - std::numbers::pi) * 0.0625;
  const double reach_perimeter = 18.0 + 4.4;
  EXPECT_LE(w.reachable_area_m2, reach_exact + 0.05);
  EXPECT_GE(w.reachable_area_m2, reach_exact - 0.05 * reach_perimeter);
  // START: the first pose clear by 0.6 m.
  EXPECT_EQ(w.start_index, 0u);
  EXPECT_DOUBLE_EQ(w.start.x_m, 1.0);
  // The WKT has START, the closed boundary and the pillar.
  const std::string wkt = to_wkt(w, {"test"});
  EXPECT_EQ(wkt.rfind("# test\n", 0), 0u);
  EXPECT_NE(wkt.find("START 1.000 1.000 0.0000"), std::string::npos);
  EXPECT_NE(wkt.find("LINESTRING("), std::string::npos);
  EXPECT_NE(wkt.find("POLYGON(("), std::string::npos);
}

TEST(World, DoorToNowhereIsClosed) {
  // The east wall has a 1.2 m opening onto nothing (no return through it).
  Room r;
  r.walls = {{0, 0, 6, 0}, {6, 0, 6, 1.4}, {6, 2.6, 6, 4}, {6, 4, 0, 4}, {0, 4, 0, 0}};
  r.poses = {{1.0, 2.0, 0.0}, {3.0, 1.0, 0.0}, {4.5, 3.0, 0.0}, {5.5, 2.0, 0.0}};
  const OccupancyGrid grid = grid_of(r);
  const World w = extract_ok(grid, r.poses);
  // One closed boundary, nothing of the region beyond the opening's line.
  EXPECT_GE(w.boundary.size(), 4u);
  EXPECT_LT(w.max_x, 6.1);
  EXPECT_FALSE(region_at(w, grid, 6.5, 2.0));
  EXPECT_LT(w.free_area_m2, 24.5);
  EXPECT_TRUE(reachable_at(w, grid, 4.5, 2.0));
  EXPECT_FALSE(reachable_at(w, grid, 6.5, 2.0));
  // With no-return beams traced free to 2 m, the region reaches out through
  // the opening as far as they went, and is closed there.
  GridOptions o;
  o.free_on_no_return = true;
  o.max_range_m = 2.0;
  const OccupancyGrid grid2 = grid_of(r, o);
  const World w2 = extract_ok(grid2, r.poses);
  EXPECT_TRUE(region_at(w2, grid2, 7.0, 2.0));
  EXPECT_LT(w2.max_x, 7.6);
  EXPECT_FALSE(region_at(w2, grid2, 8.0, 2.0));
}

TEST(World, InnerDoorStaysOpenAndGlassGapStaysAGap) {
  // Two 4 × 4 m rooms side by side; the wall between has a 1 m door at
  // y in [0.5, 1.5] and a 0.15 m gap (a glass pane the laser sees through) at
  // y in [3.0, 3.15].
  Room r;
  r.walls = box(0, 0, 8, 4);
  r.walls.push_back({4, 0, 4, 0.5});
  r.walls.push_back({4, 1.5, 4, 3.0});
  r.walls.push_back({4, 3.15, 4, 4});
  r.poses = {{2.0, 2.0, 0.0}, {1.0, 1.0, 0.0}, {3.0, 3.0, 0.0}, {6.0, 2.0, 0.0}, {5.0, 1.0, 0.0}, {7.0, 3.0, 0.0}};
  const OccupancyGrid grid = grid_of(r);
  const World w = extract_ok(grid, r.poses);
  EXPECT_TRUE(reachable_at(w, grid, 6.0, 2.0));  // through the door
  EXPECT_TRUE(reachable_at(w, grid, 4.0, 1.0));
  EXPECT_LE(w.free_area_m2, 32.0 + 0.05);
  EXPECT_GE(w.free_area_m2, 32.0 - 0.05 * (24.0 + 8.0));  // up to a cell short of every wall face
  EXPECT_TRUE(region_at(w, grid, 4.0, 3.075));    // the gap is free space...
  EXPECT_FALSE(reachable_at(w, grid, 4.0, 3.075));  // ... too narrow for the robot
  // No wall vertex closes the door.
  for (const auto& p : w.boundary) EXPECT_FALSE(p.x > 3.9 && p.x < 4.1 && p.y > 0.6 && p.y < 1.4);
}

TEST(World, SpecksSpikesAndUnseenPockets) {
  // A hand-made grid: a 2 × 2 m free square, a one-cell speck, a 4 × 4 cell
  // block of clutter, a 5-cell pocket never seen, a 1-cell-wide spike 0.5 m long.
  OccupancyGrid grid(0.0, 0.0, 80, 60, 0.05);
  for (int y = 10; y < 50; ++y)
    for (int x = 10; x < 50; ++x) grid.add(x, y, -2.0f);
  for (int x = 50; x < 60; ++x) grid.add(x, 30, -2.0f);  // the spike
  grid.add(20, 20, 4.0f);                                // the speck
  for (int y = 35; y < 39; ++y)
    for (int x = 35; x < 39; ++x) grid.add(x, y, 4.0f);  // clutter
  for (int x = 20; x < 25; ++x) grid.add(x, 40, 2.0f);   // back to unknown (log-odds 0)
  WorldOptions o;
  o.start_clearance_m = 0.2;
  o.simplify_m = 0.005;  // keep the cells' outline: areas are exact
  const World w = extract_ok(grid, {{1.5, 1.5, 0.0}}, o);
  EXPECT_EQ(w.specks_dropped, 1u);
  EXPECT_GE(w.spike_cells_cut, 10u);
  EXPECT_FALSE(w.region[30 * 80 + 55]);
  EXPECT_EQ(w.pockets_filled, 2u);  // the speck's cell and the unseen row
  ASSERT_EQ(w.obstacles.size(), 1u);
  EXPECT_NEAR(signed_area(w.obstacles[0]), 0.2 * 0.2 - 4 * 0.5 * 0.025 * 0.025, 1e-9);  // corners cut
  EXPECT_NEAR(w.free_area_m2, 4.0 - 16 * 0.0025, 1e-9);
  EXPECT_NEAR(w.min_x, 0.5, 1e-9);  // the boundary runs midway between free and non-free centres
  EXPECT_NEAR(w.max_x, 2.5, 1e-9);
}

TEST(World, BlocksTouchingAtACornerAreOneObstacle) {
  // Two 3 × 3 cell blocks of clutter touching at one corner, in a free square:
  // the free space is 4-connected, so it does not pass between them; their
  // outline is one ring (the tracer turns left at the shared corner).
  OccupancyGrid grid(0.0, 0.0, 40, 40, 0.05);
  for (int y = 5; y < 35; ++y)
    for (int x = 5; x < 35; ++x) grid.add(x, y, -2.0f);
  for (int y = 15; y < 18; ++y)
    for (int x = 15; x < 18; ++x) grid.add(x, y, 4.0f);
  for (int y = 18; y < 21; ++y)
    for (int x = 18; x < 21; ++x) grid.add(x, y, 4.0f);
  WorldOptions o;
  o.start_clearance_m = 0.2;
  o.simplify_m = 0.005;
  const World w = extract_ok(grid, {{0.5, 0.5, 0.0}}, o);
  ASSERT_EQ(w.obstacles.size(), 1u);
  // Both blocks' area, less the cut corners (at most four a block).
  EXPECT_GE(signed_area(w.obstacles[0]), 2 * (0.15 * 0.15 - 4 * 0.5 * 0.025 * 0.025) - 1e-9);
  EXPECT_LT(signed_area(w.obstacles[0]), 2 * 0.15 * 0.15);
  EXPECT_EQ(w.boundary.size(), 8u);  // a square with its corners cut
}

TEST(World, NoFreePoseIsAnError) {
  OccupancyGrid grid(0.0, 0.0, 20, 20, 0.05);
  auto r = extract_world(grid, {{0.5, 0.5, 0.0}}, {});
  ASSERT_TRUE(std::holds_alternative<std::string>(r));
}

}  // namespace
}  // namespace pex::make_world
