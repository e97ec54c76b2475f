#include "mapping/tile_grid.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "mapping/typed_ops.hpp"

namespace pex::mapping {
namespace {

using E = EdgeType;

TEST(SplitAtGrid, InsertsCrossingsExactlyOnGridLines) {
  MultiPolygon m;
  m.resize(1);
  m[0].outer() = {{-1.3, -0.7}, {9.1, 0.2}, {3.3, 7.9}, {-1.3, -0.7}};
  const double before = bg::area(m);
  split_at_grid(m, 4.0);
  EXPECT_NEAR(bg::area(m), before, 1e-9);
  int on_lines = 0;
  for (const auto& p : m[0].outer())
    if (std::fmod(p.x(), 4.0) == 0.0 || std::fmod(p.y(), 4.0) == 0.0) ++on_lines;
  EXPECT_GE(on_lines, 5);
  EXPECT_TRUE(bg::is_valid(m));
}

TEST(SplitAtGrid, PiecesOfAnEdgeKeepItsType) {
  TypedPolygon p;
  p.geometry.outer() = {{-1.3, -0.7}, {9.1, 0.2}, {3.3, 7.9}, {-1.3, -0.7}};
  p.edge_types = {{E::kObstacle, E::kFrontier, E::kObstacle}};
  const TypedPolygon before = p;
  split_at_grid(p, 4.0);
  ASSERT_TRUE(types_match_rings(p));
  EXPECT_GT(p.edge_types[0].size(), 3u);
  for_each_edge(p, [&](const Point& a, const Point& b, EdgeType t) {
    int on = 0;
    for_each_edge(before, [&](const Point& u, const Point& v, EdgeType s) {
      if (bg::distance(a, Segment(u, v)) < 1e-9 && bg::distance(b, Segment(u, v)) < 1e-9) {
        ++on;
        EXPECT_EQ(t, s);
      }
    });
    EXPECT_EQ(on, 1);
  });
}

TEST(TileGrid, BoxesShareTheirSidesBitForBit) {
  const TileGrid grid{8.0, 0.0137};
  const Box a = grid.box({-3, 2}), right = grid.box({-2, 2}), above = grid.box({-3, 3});
  EXPECT_EQ(a.max_corner().x(), right.min_corner().x());
  EXPECT_EQ(a.max_corner().y(), above.min_corner().y());
  EXPECT_EQ(grid.index(a.min_corner().x()), -3);
  EXPECT_EQ(grid.index(a.max_corner().x()), -2);  // a line belongs to the tile above it
  const auto [first, last] = grid.range(Box(Point(-0.5, 15.0), Point(8.5, 17.0)));
  EXPECT_EQ(first, (TileKey{-1, 1}));
  EXPECT_EQ(last, (TileKey{1, 2}));
}


TypedPolygon typed_ring(std::vector<Point> points, std::vector<EdgeType> types) {
  TypedPolygon p;
  p.geometry.outer().assign(points.begin(), points.end());
  p.geometry.outer().push_back(points.front());
  p.edge_types = {std::move(types)};
  return p;
}

void add_hole(TypedPolygon& p, std::vector<Point> clockwise, EdgeType type) {
  const std::size_t n = clockwise.size();
  clockwise.push_back(clockwise.front());
  p.geometry.inners().emplace_back(clockwise.begin(), clockwise.end());
  p.edge_types.emplace_back(n, type);
}

// The walk's piece and the overlay's (typed_clip) of the same split polygon
// agree: area, validity and the length of each edge type, within what the
// overlay's 1 um grid moves.
void expect_like_the_overlay(const TypedPolygon& split, const Box& box, const TypedMultiPolygon& walked) {
  const auto overlaid = typed_clip({split}, box);  // it types the box's sides kBorder itself
  ASSERT_TRUE(overlaid.ok) << overlaid.error;
  std::string why;
  EXPECT_TRUE(is_valid(walked, &why)) << why;
  const double tolerance = 1e-5 * (1.0 + bg::perimeter(split.geometry));
  EXPECT_NEAR(area(walked), area(overlaid.polygons), tolerance);
  MultiPolygon difference;
  bg::sym_difference(geometry_of(walked), geometry_of(overlaid.polygons), difference);
  EXPECT_LT(bg::area(difference), tolerance);
  for (const EdgeType t : {EdgeType::kObstacle, EdgeType::kFrontier, EdgeType::kBorder})
    EXPECT_NEAR(edge_length(walked, t), edge_length(overlaid.polygons, t), 1e-3) << to_string(t);
}

TEST(ClipSplitToTile, JoinsTheRunsInsideAlongTheSides) {
  // A U whose arms cross the tile's top side: two pieces, each closed along it.
  const Box tile(Point(0, 0), Point(8, 8));
  TypedPolygon u = typed_ring({{2, 2}, {6, 2}, {6, 10}, {5, 10}, {5, 4}, {3, 4}, {3, 10}, {2, 10}},
                              {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle,
                               E::kFrontier, E::kObstacle});
  split_at_grid(u, 8.0);
  TypedMultiPolygon walked;
  ASSERT_TRUE(clip_split_to_tile(u, tile, walked));
  ASSERT_EQ(walked.size(), 1u);
  EXPECT_DOUBLE_EQ(area(walked), 4 * 2 + 2 * 4);
  EXPECT_DOUBLE_EQ(edge_length(walked, E::kBorder), 2.0);  // the two arms' ends on the top side
  expect_like_the_overlay(u, tile, walked);
  // The tile above holds the arms' upper ends, two pieces.
  TypedMultiPolygon above;
  ASSERT_TRUE(clip_split_to_tile(u, Box(Point(0, 8), Point(8, 16)), above));
  EXPECT_EQ(above.size(), 2u);
  expect_like_the_overlay(u, Box(Point(0, 8), Point(8, 16)), above);
}

TEST(ClipSplitToTile, ABoxInsideThePolygonKeepsTheHolesInIt) {
  const Box tile(Point(0, 0), Point(8, 8));
  TypedPolygon room = typed_ring({{-4, -4}, {12, -4}, {12, 12}, {-4, 12}}, std::vector<E>(4, E::kObstacle));
  add_hole(room, {{3, 3}, {3, 5}, {5, 5}, {5, 3}}, E::kObstacle);     // inside the tile
  add_hole(room, {{7, 3}, {7, 5}, {9, 5}, {9, 3}}, E::kFrontier);     // across its right side
  split_at_grid(room, 8.0);
  TypedMultiPolygon walked;
  ASSERT_TRUE(clip_split_to_tile(room, tile, walked));
  ASSERT_EQ(walked.size(), 1u);
  EXPECT_EQ(walked[0].geometry.inners().size(), 1u);  // the other hole is a notch in the side
  EXPECT_DOUBLE_EQ(area(walked), 64 - 4 - 2);
  expect_like_the_overlay(room, tile, walked);
  // A tile deep inside the room without holes is the tile; one outside it is nothing.
  TypedMultiPolygon deep, beyond;
  TypedPolygon plain = typed_ring({{-20, -20}, {28, -20}, {28, 28}, {-20, 28}}, std::vector<E>(4, E::kFrontier));
  split_at_grid(plain, 8.0);
  ASSERT_TRUE(clip_split_to_tile(plain, tile, deep));
  ASSERT_EQ(deep.size(), 1u);
  EXPECT_DOUBLE_EQ(area(deep), 64.0);
  EXPECT_DOUBLE_EQ(edge_length(deep, E::kBorder), 32.0);
  ASSERT_TRUE(clip_split_to_tile(plain, Box(Point(40, 0), Point(48, 8)), beyond));
  EXPECT_TRUE(beyond.empty());
}

TEST(ClipSplitToTile, EdgesOnASideWithTheInsideTowardsTheTileAreKeptAsBorder) {
  const Box tile(Point(0, 0), Point(8, 8));
  // Inside the tile, one edge on its bottom side: kept, typed border.
  TypedMultiPolygon inside;
  const TypedPolygon on_bottom = typed_ring({{2, 0}, {6, 0}, {6, 3}, {2, 3}}, std::vector<E>(4, E::kObstacle));
  ASSERT_TRUE(clip_split_to_tile(on_bottom, tile, inside));
  ASSERT_EQ(inside.size(), 1u);
  EXPECT_DOUBLE_EQ(edge_length(inside, E::kBorder), 4.0);
  EXPECT_DOUBLE_EQ(edge_length(inside, E::kObstacle), 10.0);
  // Below the tile, the same edge the other way: the overlay's to clip (a
  // polygon may run along a side both ways, a spike a hair wide, which only
  // the overlay's grid closes: fuzz/corpus/typed_ops/tile-clip-spike-along-side).
  TypedMultiPolygon below;
  const TypedPolygon under = typed_ring({{2, -3}, {6, -3}, {6, 0}, {2, 0}}, std::vector<E>(4, E::kObstacle));
  EXPECT_FALSE(clip_split_to_tile(under, tile, below));
  EXPECT_TRUE(below.empty());
}

TEST(ClipSplitToTile, LeavesToTheOverlayWhatTheWalkCannotTell) {
  const Box tile(Point(0, 0), Point(8, 8));
  TypedMultiPolygon out;
  // Not split at the tile's lines: an edge from inside the tile to beyond it.
  const TypedPolygon unsplit = typed_ring({{2, 2}, {10, 2}, {10, 4}, {2, 4}}, std::vector<E>(4, E::kObstacle));
  EXPECT_FALSE(clip_split_to_tile(unsplit, tile, out));
  // Across the tile between two points outside it.
  const TypedPolygon across = typed_ring({{-2, 2}, {10, 2}, {10, 4}, {-2, 4}}, std::vector<E>(4, E::kObstacle));
  EXPECT_FALSE(clip_split_to_tile(across, tile, out));
  // Touching the bottom side from inside at a vertex.
  const TypedPolygon touching = typed_ring({{2, 4}, {4, 0}, {6, 4}, {4, 6}}, std::vector<E>(4, E::kObstacle));
  TypedPolygon split = typed_ring({{-2, 4}, {4, 0}, {10, 4}, {10, 10}, {-2, 10}}, std::vector<E>(5, E::kObstacle));
  split_at_grid(split, 8.0);
  EXPECT_FALSE(clip_split_to_tile(split, tile, out));
  EXPECT_TRUE(out.empty());  // untouched when it declines
  // ... which a polygon wholly inside the tile may do: it is the piece.
  EXPECT_TRUE(clip_split_to_tile(touching, tile, out));
  EXPECT_EQ(out.size(), 1u);
  // A hole touching the outer ring at a point inside the tile (valid): the
  // piece's ring would pass through that point twice (fuzz/corpus/typed_ops/
  // tile-clip-hole-*).
  TypedPolygon notched = typed_ring({{-4, -4}, {4, -4}, {4, 4}, {-4, 4}}, std::vector<E>(4, E::kObstacle));
  add_hole(notched, {{4, 4}, {3, 2}, {2, 3}}, E::kFrontier);
  ASSERT_TRUE(is_valid(notched));
  split_at_grid(notched, 8.0);
  TypedMultiPolygon none;
  EXPECT_FALSE(clip_split_to_tile(notched, Box(Point(0, 0), Point(8, 8)), none));
  EXPECT_TRUE(none.empty());
  // A vertex a hair off a side: the overlay snaps that notch away.
  const TypedPolygon hair = typed_ring({{2, 2}, {6, 2}, {6, 8 - 1e-9}, {2, 6}}, std::vector<E>(4, E::kObstacle));
  EXPECT_FALSE(clip_split_to_tile(hair, tile, none));
}

// Scan-like polygons (stars of random ranges, ragged or smooth, with runs
// of random types) with small holes, split at a random grid and clipped to
// every tile they meet: the walk agrees with the overlay wherever it clips,
// and it clips nearly all.
TEST(ClipSplitToTile, RandomPolygonsAgreeWithTheOverlay) {
  std::mt19937_64 rng(20261128);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int walked_tiles = 0, declined = 0, with_holes = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double cx = 20 * unit(rng) - 10, cy = 20 * unit(rng) - 10;
    const int n = 40 + static_cast<int>(160 * unit(rng));
    const bool ragged = trial % 2 == 0;
    std::vector<Point> points;
    std::vector<EdgeType> types;
    EdgeType type = E::kObstacle;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      const double r = ragged ? 1.0 + 7.0 * unit(rng) : 7.0 + 0.5 * unit(rng);
      points.emplace_back(cx + r * std::cos(a), cy + r * std::sin(a));
      if (unit(rng) < 0.2) type = type == E::kObstacle ? E::kFrontier : E::kObstacle;
      types.push_back(type);
    }
    TypedPolygon polygon = typed_ring(points, types);
    // Small holes (a pillar each) where they fit, across tile lines as they fall.
    for (int h = 0; h < 4; ++h) {
      const double a = 2 * std::numbers::pi * unit(rng), d = 6.0 * unit(rng), r = 0.2 + 0.6 * unit(rng);
      std::vector<Point> hole;
      for (int i = 0; i < 10; ++i) {
        const double b = -2 * std::numbers::pi * i / 10;
        hole.emplace_back(cx + d * std::cos(a) + r * std::cos(b), cy + d * std::sin(a) + r * std::sin(b));
      }
      TypedPolygon with = polygon;
      add_hole(with, hole, unit(rng) < 0.5 ? E::kFrontier : E::kObstacle);
      if (is_valid(with)) polygon = std::move(with);
    }
    with_holes += polygon.geometry.inners().empty() ? 0 : 1;
    ASSERT_TRUE(is_valid(polygon));
    const double size = trial % 3 == 0 ? 8.0 : 1.5 + 3 * unit(rng);
    const TileGrid grid{size, 10 * unit(rng) - 5};
    split_at_grid(polygon, grid.size_m, grid.origin_m);
    const auto [first, last] = grid.range(bg::return_envelope<Box>(polygon.geometry));
    for (auto i = first.first; i <= last.first; ++i)
      for (auto j = first.second; j <= last.second; ++j) {
        const Box box = grid.box({i, j});
        TypedMultiPolygon walked;
        if (!clip_split_to_tile(polygon, box, walked)) {
          ++declined;
          continue;
        }
        ++walked_tiles;
        expect_like_the_overlay(polygon, box, walked);
        if (HasFailure()) return;
      }
  }
  std::printf("walked %d tiles, declined %d, %d polygons with holes\n", walked_tiles, declined, with_holes);
  EXPECT_GT(with_holes, 200);
  EXPECT_GT(walked_tiles, 5000);
  EXPECT_LT(declined, walked_tiles / 100);
}

}  // namespace
}  // namespace pex::mapping
