#include "mapping/tile_grid.hpp"

#include <cmath>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace pex::mapping
