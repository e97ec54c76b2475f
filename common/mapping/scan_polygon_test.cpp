#include "mapping/scan_polygon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mapping/test_support.hpp"

namespace pex::mapping {
namespace {

using geometry::Pose2;

using testing::add_box;
using testing::cast_scan;
using testing::ScanSpec;
using testing::Wall;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

double distance_to_walls(const Point& p, const std::vector<Wall>& walls) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& w : walls) best = std::min(best, bg::distance(p, Segment(w.a, w.b)));
  return best;
}

ScanPolygonResult build(const std::vector<float>& ranges, const ScanSpec& spec, const Pose2& pose,
                        ScanPolygonOptions options = {}) {
  options.range_max_m = spec.range_max_m;
  return scan_to_polygon(ranges, spec.angle_min, spec.angle_increment, pose, options);
}

// A straight wall close to the sensor, seen near normal incidence with the
// LMS111's range noise: the returns are 4 mm apart and scatter +-3 cm across
// the wall, so RDP alone splits at single noisy returns into a zigzag of short
// edges across the wall. The merge step must leave edges along the wall.
TEST(ScanToPolygon, NoisyWallCloseByGivesEdgesAlongTheWall) {
  std::vector<Wall> walls{{Point(-3, 0.5), Point(3, 0.5)}};
  const ScanSpec spec;
  std::mt19937_64 rng(21);
  for (int k = 0; k < 20; ++k) {
    const Pose2 pose{0.0, 0.0, 1.57};
    const auto result = build(cast_scan(walls, pose, spec, 0.012, &rng), spec, pose);
    ASSERT_TRUE(result.ok) << result.error;
    int steep = 0, obstacle = 0;
    for_each_edge(result.polygon, [&](const Point& a, const Point& b, EdgeType t) {
      if (t != EdgeType::kObstacle || std::min(a.x(), b.x()) > 1.0 || std::max(a.x(), b.x()) < -1.0) return;
      ++obstacle;
      if (std::abs(b.y() - a.y()) > std::abs(b.x() - a.x())) ++steep;  // more than 45 deg off the wall
    });
    EXPECT_GT(obstacle, 0);
    EXPECT_EQ(steep, 0) << "scan " << k;
  }
}

TEST(ScanToPolygon, RoomSeenFromInsideHasObstacleEdgesOnTheWalls) {
  std::vector<Wall> walls;
  add_box(walls, 0, 0, 6, 4);
  const ScanSpec spec;
  const Pose2 pose{2.0, 1.5, 0.3};
  const auto result = build(cast_scan(walls, pose, spec), spec, pose);
  ASSERT_TRUE(result.ok) << result.error;
  EXPECT_EQ(result.fallback_level, 0);
  EXPECT_TRUE(is_valid(result.polygon));
  const TypedMultiPolygon map{result.polygon};
  // Every obstacle edge lies on a wall (noise-free: up to the fit's rounding).
  double obstacle_length = 0.0;
  for_each_edge(map, [&](const Point& a, const Point& b, EdgeType t) {
    if (t != EdgeType::kObstacle) return;
    obstacle_length += bg::distance(a, b);
    EXPECT_LT(distance_to_walls(a, walls), 0.01);
    EXPECT_LT(distance_to_walls(b, walls), 0.01);
  });
  // The 270-degree scan sees most of the 20 m of walls; the area it saw is
  // within the room and most of it.
  EXPECT_GT(obstacle_length, 12.0);
  EXPECT_LE(area(map), 24.0 + 1e-6);
  EXPECT_GT(area(map), 15.0);
  // The sensor origin is a vertex and both its edges are frontiers.
  const auto& ring = result.polygon.geometry.outer();
  EXPECT_NEAR(ring.front().x(), pose.x_m, 1e-12);
  EXPECT_NEAR(ring.front().y(), pose.y_m, 1e-12);
  EXPECT_EQ(result.polygon.edge_types[0].front(), EdgeType::kFrontier);
  EXPECT_EQ(result.polygon.edge_types[0].back(), EdgeType::kFrontier);
  // RDP + refit: a handful of vertices, not one per beam.
  EXPECT_LT(vertex_count(result.polygon.geometry), 20u);
}

TEST(ScanToPolygon, NoReturnBeamsEndAtTheFreeRangeAsFrontier) {
  const ScanSpec spec;
  std::vector<float> ranges(static_cast<std::size_t>(spec.beams), kInf);
  ranges[3] = kNaN;
  ranges[4] = -1.0f;
  ranges[5] = 0.0f;
  ranges[6] = 1e9f;
  ScanPolygonOptions options;
  options.free_range_m = 3.0;
  const auto result = build(ranges, spec, {}, options);
  ASSERT_TRUE(result.ok) << result.error;
  EXPECT_EQ(result.beams_returned, 0);
  const TypedMultiPolygon map{result.polygon};
  EXPECT_DOUBLE_EQ(edge_length(map, EdgeType::kObstacle), 0.0);
  const double span = spec.angle_increment * (spec.beams - 1);
  const double sector = 0.5 * span * 9.0;
  EXPECT_NEAR(area(map), sector, 0.02 * sector);
}

// A corridor wall with a 0.85 m door, seen along its length from 16 m
// away (the sensor 2.66 m off the wall): its returns are about 0.9 m apart
// there, no beam passes the door, and the adaptive break distance (0.9 m at
// that range) joined the returns on either side of the door into one wall.
// Its obstacle band then closed the door in the planning map for good (a
// room lost on a generated building, docs/mapping.md). With the cap the
// door's line is frontier, the walls beside it stay obstacle.
TEST(ScanToPolygon, AWallSeenAlongItsLengthFromAfarIsNotDrawnAcrossADoor) {
  std::vector<Wall> walls{{Point(0.0, -12.0), Point(0.0, 6.25)}, {Point(0.0, 7.10), Point(0.0, 12.0)},  // the door: y 6.25-7.10
                          {Point(0.0, 12.0), Point(-6.0, 12.0)}, {Point(-6.0, 12.0), Point(-6.0, 4.0)},   // the room behind it
                          {Point(-6.0, 4.0), Point(0.0, 4.0)}, {Point(5.0, -12.0), Point(5.0, 12.0)}};   // the corridor's far wall
  ScanSpec spec;
  spec.range_max_m = 20.0;
  const Pose2 pose{2.66, -9.675, 1.5707963};  // beams meet the wall at y 6.22 and 7.12, none in the door
  const Segment doorway(Point(-0.1, 6.675), Point(0.1, 6.675));  // across the door, at its middle
  auto obstacle_across_the_door = [&](const ScanPolygonResult& r) {
    bool across = false;
    for_each_edge(r.polygon, [&](const Point& a, const Point& b, EdgeType t) {
      if (t == EdgeType::kObstacle && bg::intersects(Segment(a, b), doorway)) across = true;
    });
    return across;
  };
  // Obstacle length on the wall between y0 and y1.
  auto obstacle_on_the_wall = [&](const ScanPolygonResult& r, double y0, double y1) {
    double length = 0.0;
    for_each_edge(r.polygon, [&](const Point& a, const Point& b, EdgeType t) {
      if (t == EdgeType::kObstacle && std::abs(a.x()) < 0.05 && std::abs(b.x()) < 0.05)
        length += std::max(0.0, std::min(y1, std::max(a.y(), b.y())) - std::max(y0, std::min(a.y(), b.y())));
    });
    return length;
  };
  const auto ranges = cast_scan(walls, pose, spec);
  const auto uncapped = build(ranges, spec, pose);
  ASSERT_TRUE(uncapped.ok) << uncapped.error;
  ASSERT_TRUE(obstacle_across_the_door(uncapped)) << "the case: the adaptive break alone draws the wall across the door";
  ScanPolygonOptions options;
  options.break_max_gap_m = 0.5;
  const auto capped = build(ranges, spec, pose, options);
  ASSERT_TRUE(capped.ok) << capped.error;
  EXPECT_FALSE(obstacle_across_the_door(capped));
  // Where its returns are closer together than the cap (within 10 m here) the
  // wall is one wall as before; farther along, seen ever more along its
  // length, it is pieces with frontier between them, to be seen better nearer.
  EXPECT_NEAR(obstacle_on_the_wall(capped, -8.0, -2.0), 6.0, 1e-6);
  EXPECT_NEAR(obstacle_on_the_wall(uncapped, -8.0, -2.0), 6.0, 1e-6);
  EXPECT_LT(obstacle_on_the_wall(capped, 0.0, 6.0), obstacle_on_the_wall(uncapped, 0.0, 6.0));
  // The free space is the same polygon: only the type of its edges changed.
  EXPECT_NEAR(bg::area(capped.polygon.geometry), bg::area(uncapped.polygon.geometry), 1e-6);
}

// A room 3 m deep and 16 m wide seen from its middle: the near wall is drawn,
// the side walls beyond the obstacle range are not, and their beams end in a
// frontier at that range (free space seen, the wall to be seen from nearer).
TEST(ScanToPolygon, ReturnsBeyondTheObstacleRangeGiveFreeSpaceToItNotWalls) {
  std::vector<Wall> walls;
  add_box(walls, -8, -3, 8, 3);
  const ScanSpec spec;
  const Pose2 pose{0.0, 0.0, 1.5707963};
  ScanPolygonOptions options;
  options.obstacle_range_m = 5.0;
  const auto result = build(cast_scan(walls, pose, spec), spec, pose, options);
  ASSERT_TRUE(result.ok) << result.error;
  EXPECT_GT(result.beams_beyond_obstacle_range, 0);
  EXPECT_GT(result.beams_returned, 0);
  bool far_obstacle = false;
  double frontier_at_cut = 0.0;
  for_each_edge(result.polygon, [&](const Point& a, const Point& b, EdgeType t) {
    const double ra = std::hypot(a.x(), a.y()), rb = std::hypot(b.x(), b.y());
    if (t == EdgeType::kObstacle && std::max(ra, rb) > 5.0 + 1e-6) far_obstacle = true;
    if (t == EdgeType::kFrontier && std::abs(ra - 5.0) < 1e-6 && std::abs(rb - 5.0) < 1e-6)
      frontier_at_cut += bg::distance(a, b);
  });
  EXPECT_FALSE(far_obstacle);
  EXPECT_GT(frontier_at_cut, 1.0);
  // Free space reaches the cut along the room, not past it; the near wall bounds it.
  EXPECT_TRUE(bg::within(Point(4.9, 0.0), result.polygon.geometry));
  EXPECT_TRUE(bg::within(Point(-4.9, 0.0), result.polygon.geometry));
  EXPECT_FALSE(bg::within(Point(5.2, 0.0), result.polygon.geometry));
  EXPECT_FALSE(bg::within(Point(0.0, 3.1), result.polygon.geometry));

  // Without the cut the same scan draws the side walls 8 m away.
  const auto whole = build(cast_scan(walls, pose, spec), spec, pose);
  ASSERT_TRUE(whole.ok) << whole.error;
  EXPECT_EQ(whole.beams_beyond_obstacle_range, 0);
  EXPECT_TRUE(bg::within(Point(7.5, 0.0), whole.polygon.geometry));
}

// The map is the union of scans: at a wall it keeps the farthest free space
// any scan ever put there. A long straight wall is fitted from many returns
// and the noise averages out, but a ragged one (the Intel lab's walls and
// clutter: short pieces, a few returns each) keeps single noisy returns as
// vertices, and seen 300 times with the LMS111's 12 mm range noise its
// free-space envelope lies centimetres beyond it. With returns taken 2 sigma
// nearer the sensor the envelope stays on the wall.
TEST(ScanToPolygon, AReturnMarginKeepsTheUnionOfNoisyScansOnARaggedWall) {
  // A ragged wall: 6 cm flats alternately at y = 1.50 and 1.46, joined by steps.
  std::vector<Wall> walls;
  add_box(walls, -6, -1.5, 6, 0.0);  // the corridor's other walls (its top at y = 0 is replaced below)
  std::erase_if(walls, [](const Wall& w) { return w.a.y() == 0.0 && w.b.y() == 0.0; });
  walls.push_back({Point(-6, 0.0), Point(-6, 1.5)});
  walls.push_back({Point(6, 0.0), Point(6, 1.5)});
  auto wall_y = [](int i) { return i % 2 == 0 ? 1.50 : 1.46; };
  for (int i = 0; i < 200; ++i) {
    const double x0 = -6.0 + 0.06 * i, x1 = x0 + 0.06;
    walls.push_back({Point(x0, wall_y(i)), Point(x1, wall_y(i))});
    if (i + 1 < 200) walls.push_back({Point(x1, wall_y(i)), Point(x1, wall_y(i + 1))});
  }
  const ScanSpec spec;
  // How far beyond the wall the union of the scans' free space reaches at the
  // middle of each flat over x in [-2, 2].
  auto envelope_beyond_wall = [&](double margin_m) {
    std::mt19937_64 rng(5);
    ScanPolygonOptions options;
    options.return_margin_m = margin_m;
    std::vector<double> reach;
    std::vector<int> flat;
    for (int i = 0; i < 200; ++i) {
      const double x = -6.0 + 0.06 * i + 0.03;
      if (x > -2.0 && x < 2.0) flat.push_back(i), reach.push_back(-1.0);
    }
    for (int k = 0; k < 300; ++k) {
      const Pose2 pose{-1.0 + 2.0 * (k % 30) / 29.0, -0.4 + 0.1 * (k % 7), 0.05 * (k % 5)};
      const auto result = build(cast_scan(walls, pose, spec, 0.012, &rng), spec, pose, options);
      EXPECT_TRUE(result.ok) << result.error;
      for (std::size_t j = 0; j < flat.size(); ++j) {
        const double x = -6.0 + 0.06 * flat[j] + 0.03;
        const bg::model::linestring<Point> probe{Point(x, 1.2), Point(x, 1.8)};
        bg::model::multi_linestring<bg::model::linestring<Point>> inside;
        bg::intersection(probe, result.polygon.geometry, inside);
        for (const auto& piece : inside)
          for (const auto& c : piece) reach[j] = std::max(reach[j], c.y() - wall_y(flat[j]));
      }
    }
    double sum = 0.0;
    for (const double r : reach) sum += r;
    return sum / static_cast<double>(reach.size());
  };
  const double raw = envelope_beyond_wall(0.0);
  const double kept = envelope_beyond_wall(0.025);
  EXPECT_GT(raw, 0.02) << "the noise's far envelope, measured without the margin";
  EXPECT_LT(kept, raw - 0.015);
  EXPECT_LT(std::abs(kept), 0.015) << "with the margin the envelope is on the wall, free space still reaches it";
}

TEST(ScanToPolygon, RefusesBadInputWithAnError) {
  const ScanSpec spec;
  const std::vector<float> ranges(10, 2.0f);
  auto expect_error = [](const ScanPolygonResult& r) {
    EXPECT_FALSE(r.ok);
    EXPECT_FALSE(r.error.empty());
  };
  ScanPolygonOptions o;
  expect_error(scan_to_polygon(std::vector<float>{1.0f}, 0, 0.1, {}, o));
  expect_error(scan_to_polygon(ranges, 0, 0.0, {}, o));
  expect_error(scan_to_polygon(ranges, std::nan(""), 0.1, {}, o));
  expect_error(scan_to_polygon(ranges, 0, 0.1, {std::nan(""), 0, 0}, o));
  // Steps of a turn or more: no two beams within one turn (a step beyond
  // 4 pi made the beam count -1, converted to size_t: the fuzzer's finding).
  expect_error(scan_to_polygon(ranges, 0, 7.0, {}, o));
  expect_error(scan_to_polygon(ranges, 0, -20.0, {}, o));
  expect_error(scan_to_polygon(ranges, 0, 1e300, {}, o));
  o.max_beams = 5;
  expect_error(scan_to_polygon(ranges, 0, 0.1, {}, o));
}

TEST(ScanToPolygon, NegativeIncrementGivesTheSamePolygonArea) {
  std::vector<Wall> walls;
  add_box(walls, -3, -2, 4, 5);
  ScanSpec spec;
  const Pose2 pose{0.5, 0.5, 1.0};
  auto ranges = cast_scan(walls, pose, spec);
  const auto forward = build(ranges, spec, pose);
  std::reverse(ranges.begin(), ranges.end());
  ScanSpec reversed = spec;
  reversed.angle_min = spec.angle_min + spec.angle_increment * (spec.beams - 1);
  reversed.angle_increment = -spec.angle_increment;
  const auto backward = build(ranges, reversed, pose);
  ASSERT_TRUE(forward.ok && backward.ok);
  EXPECT_NEAR(bg::area(forward.polygon.geometry), bg::area(backward.polygon.geometry), 1e-9);
}

TEST(ScanToPolygon, FullTurnScannerStaysSimple) {
  std::vector<Wall> walls;
  add_box(walls, -3, -2, 4, 5);
  ScanSpec spec;
  spec.angle_min = -std::numbers::pi;
  spec.beams = 721;  // the last beam repeats the first
  const Pose2 pose{0.5, 0.5, 0.0};
  const auto result = build(cast_scan(walls, pose, spec), spec, pose);
  ASSERT_TRUE(result.ok) << result.error;
  EXPECT_TRUE(is_valid(result.polygon));
  EXPECT_GT(bg::area(result.polygon.geometry), 0.9 * 35.0);
}

TEST(ScanToPolygon, DeterministicBitForBit) {
  std::mt19937_64 rng(7);
  const auto walls = testing::random_room(12, 9, 8, rng);
  const ScanSpec spec;
  const Pose2 pose{4.0, 4.0, 0.7};
  std::mt19937_64 noise_a(3), noise_b(3);
  const auto a = build(cast_scan(walls, pose, spec, 0.02, &noise_a), spec, pose);
  const auto b = build(cast_scan(walls, pose, spec, 0.02, &noise_b), spec, pose);
  ASSERT_TRUE(a.ok && b.ok);
  ASSERT_EQ(a.polygon.geometry.outer().size(), b.polygon.geometry.outer().size());
  for (std::size_t i = 0; i < a.polygon.geometry.outer().size(); ++i) {
    EXPECT_EQ(a.polygon.geometry.outer()[i].x(), b.polygon.geometry.outer()[i].x());
    EXPECT_EQ(a.polygon.geometry.outer()[i].y(), b.polygon.geometry.outer()[i].y());
  }
  EXPECT_EQ(a.polygon.edge_types, b.polygon.edge_types);
}

// Garbage in (random ranges, NaN, inf, negative, huge, noise on walls):
// always a valid simple polygon or an explicit error, never an invalid ring.
TEST(ScanToPolygon, RandomScansGiveValidPolygonsOrErrors) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto walls = testing::random_room(15, 10, 12, rng);
  int ok = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    ScanSpec spec;
    spec.beams = 2 + static_cast<int>(u(rng) * 700);
    spec.angle_increment = (u(rng) < 0.1 ? -1 : 1) * (0.001 + u(rng) * 0.02);
    spec.angle_min = -u(rng) * 4.0;
    const Pose2 pose{1 + 13 * u(rng), 1 + 8 * u(rng), 6.28 * u(rng)};
    std::vector<float> ranges;
    if (trial % 2 == 0) {
      ranges = cast_scan(walls, pose, spec, 0.03 * u(rng), &rng);
    } else {
      ranges.resize(static_cast<std::size_t>(spec.beams));
      for (auto& r : ranges) {
        const double k = u(rng);
        r = k < 0.05 ? kNaN : k < 0.1 ? kInf : k < 0.15 ? -1.0f : static_cast<float>(u(rng) * 12);
      }
    }
    const auto result = build(ranges, spec, pose);
    if (!result.ok) {
      EXPECT_FALSE(result.error.empty());
      continue;
    }
    ++ok;
    std::string why;
    ASSERT_TRUE(is_valid(result.polygon, &why)) << "trial " << trial << ": " << why;
    EXPECT_GT(bg::area(result.polygon.geometry), 0.0);
  }
  EXPECT_GT(ok, 2900);
}

}  // namespace
}  // namespace pex::mapping
