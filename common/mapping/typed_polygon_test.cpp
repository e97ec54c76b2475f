#include "mapping/typed_polygon.hpp"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace pex::mapping {
namespace {

using E = EdgeType;

// A counter-clockwise ring from points (closing point added) with types.
TypedPolygon make(std::vector<Point> points, std::vector<EdgeType> types) {
  TypedPolygon p;
  p.geometry.outer().assign(points.begin(), points.end());
  p.geometry.outer().push_back(points.front());
  p.edge_types.push_back(std::move(types));
  return p;
}

TEST(TypedPolygon, CountsAreaAndLengths) {
  const auto square = make({{0, 0}, {2, 0}, {2, 2}, {0, 2}}, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle});
  const TypedMultiPolygon map{square};
  EXPECT_EQ(vertex_count(map), 4u);
  EXPECT_DOUBLE_EQ(area(map), 4.0);
  EXPECT_DOUBLE_EQ(edge_length(map, E::kObstacle), 6.0);
  EXPECT_DOUBLE_EQ(edge_length(map, E::kFrontier), 2.0);
  EXPECT_TRUE(is_valid(map));
}

TEST(TypedPolygon, TypeCountMismatchIsInvalid) {
  auto square = make({{0, 0}, {2, 0}, {2, 2}, {0, 2}}, {E::kObstacle, E::kFrontier, E::kObstacle});
  std::string why;
  EXPECT_FALSE(is_valid(square, &why));
  EXPECT_FALSE(why.empty());
}

TEST(TypedPolygon, ClockwiseOuterRingIsInvalid) {
  const auto square = make({{0, 0}, {0, 2}, {2, 2}, {2, 0}}, {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle});
  EXPECT_FALSE(is_valid(square));
}

TEST(TypedPolygon, SimplifyRemovesCollinearVerticesWithinOneType) {
  // Bottom side: 5 collinear obstacle vertices; right side: frontier.
  const auto p = make({{0, 0}, {1, 0.001}, {2, 0}, {3, -0.001}, {4, 0}, {4, 4}, {0, 4}},
                      {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier,
                       E::kObstacle, E::kObstacle});
  const auto s = simplify_typed(TypedMultiPolygon{p}, 0.01);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(vertex_count(s), 4u);
  EXPECT_TRUE(is_valid(s));
  EXPECT_NEAR(edge_length(s, E::kFrontier), 4.0, 1e-9);
}

TEST(TypedPolygon, SimplifyNeverMergesAcrossATypeChange) {
  // Collinear bottom side whose middle vertex separates obstacle from frontier.
  const auto p = make({{0, 0}, {2, 0}, {4, 0}, {4, 4}, {0, 4}},
                      {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle});
  const auto s = simplify_typed(TypedMultiPolygon{p}, 0.5);
  EXPECT_EQ(vertex_count(s), 5u);
  EXPECT_NEAR(edge_length(s, E::kFrontier), 2.0, 1e-12);
  EXPECT_NEAR(edge_length(s, E::kObstacle), 14.0, 1e-12);
}

TEST(TypedPolygon, SimplifyKeepsTheInputWhenTheResultWouldBeInvalid) {
  // A thin spike: RDP with a large tolerance would collapse the ring.
  const auto p = make({{0, 0}, {10, 0}, {10, 0.01}, {0, 0.02}},
                      {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle});
  const auto s = simplify_typed(TypedMultiPolygon{p}, 1.0);
  EXPECT_TRUE(is_valid(s));
  EXPECT_GT(area(s), 0.0);
}

// Pieces far below epsilon where the type changes (an overlay of nearly
// collinear edges leaves them) are merged into a neighbour, never moving a
// vertex of a border edge; a piece cutting off a corner between two border
// edges is replaced by the corner.
TEST(TypedPolygon, SimplifyMergesPiecesFarBelowEpsilonAtTypeChanges) {
  // Bottom side: obstacle, a 2e-8 m frontier piece, obstacle; right side
  // frontier, top obstacle, left border.
  const auto p = make({{0, 0}, {2, 0}, {2 + 2e-8, 1e-9}, {4, 0}, {4, 4}, {0, 4}},
                      {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kBorder});
  const auto s = simplify_typed(TypedMultiPolygon{p}, 0.01);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_TRUE(is_clearly_valid(s));  // before: the piece was below its clearance
  EXPECT_EQ(vertex_count(s), 4u);
  EXPECT_NEAR(edge_length(s, E::kObstacle), 8.0, 1e-6);
  EXPECT_NEAR(edge_length(s, E::kFrontier), 4.0, 1e-6);
  EXPECT_DOUBLE_EQ(edge_length(s, E::kBorder), 4.0);  // the border vertices did not move
  // Without the merge RDP would keep both ends of the piece (a type change).
  const auto unmerged = simplify_typed(TypedMultiPolygon{p}, 1e-12);
  EXPECT_EQ(vertex_count(unmerged), 6u);
}

TEST(TypedPolygon, SimplifyKeepsBorderVerticesAndRestoresACutOffCorner) {
  // A tile [0, 4]^2 whose free polygon misses a 1e-8 m triangle at (0, 0):
  // border, border, a frontier piece across the corner, border.
  const auto cut = make({{1e-8, 0}, {4, 0}, {4, 4}, {0, 4}, {0, 1e-8}},
                        {E::kBorder, E::kBorder, E::kBorder, E::kBorder, E::kFrontier});
  const auto s = simplify_typed(TypedMultiPolygon{cut}, 0.01);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_TRUE(is_clearly_valid(s));
  EXPECT_EQ(vertex_count(s), 4u);
  EXPECT_DOUBLE_EQ(edge_length(s, E::kBorder), 16.0);
  EXPECT_DOUBLE_EQ(bg::area(s[0].geometry), 16.0);  // the corner is exactly (0, 0)
  // A short piece between a border edge and another type: the border
  // vertex stays where it is, the piece's other end goes.
  const auto side = make({{0, 0}, {4, 0}, {4, 4}, {2e-8, 4}, {0, 4 - 1e-8}},
                         {E::kObstacle, E::kBorder, E::kBorder, E::kFrontier, E::kObstacle});
  const auto t = simplify_typed(TypedMultiPolygon{side}, 0.01);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_TRUE(is_valid(t));
  bool border_corner_kept = false;
  for (const auto& v : t[0].geometry.outer()) border_corner_kept |= v.x() == 2e-8 && v.y() == 4.0;
  EXPECT_TRUE(border_corner_kept);
  EXPECT_EQ(vertex_count(t), 4u);
}

TEST(TypedPolygon, SimplifyDropsAHoleSmallerThanTheShortestEdgeKept) {
  // A room with a 1.3 um speck of a hole (types kept from the overlay that
  // cut it) and a 1 m pillar.
  auto room = make({{0, 0}, {10, 0}, {10, 10}, {0, 10}}, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle});
  room.geometry.inners().push_back(Ring{{5, 5}, {5 + 1e-6, 5 + 1.3e-6}, {5 + 1e-6, 5}, {5, 5}});
  room.edge_types.push_back({E::kObstacle, E::kFrontier, E::kFrontier});
  room.geometry.inners().push_back(Ring{{2, 2}, {2, 3}, {3, 3}, {3, 2}, {2, 2}});
  room.edge_types.push_back({E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle});
  ASSERT_TRUE(is_valid(TypedMultiPolygon{room}));
  const auto s = simplify_typed(TypedMultiPolygon{room}, 0.01);
  ASSERT_EQ(s.size(), 1u);
  ASSERT_EQ(s[0].geometry.inners().size(), 1u);
  EXPECT_EQ(s[0].edge_types.size(), 2u);
  EXPECT_DOUBLE_EQ(bg::area(s[0].geometry), 99.0);
  EXPECT_TRUE(is_clearly_valid(s));
}

TEST(TypedPolygon, UniformTypeCoversHoles) {
  Polygon g;
  bg::read_wkt("POLYGON((0 0,10 0,10 10,0 10,0 0),(2 2,2 4,4 4,4 2,2 2))", g);
  bg::correct(g);
  const auto typed = with_uniform_type(MultiPolygon{g}, E::kObstacle);
  ASSERT_TRUE(is_valid(typed));
  EXPECT_EQ(vertex_count(typed), 8u);
  EXPECT_DOUBLE_EQ(edge_length(typed, E::kObstacle), 48.0);
}

// is_clearly_valid is a shortcut in front of bg::is_valid: whatever it
// accepts, Boost must accept too. Random rings (star-shaped: simple; random
// order: mostly self-crossing), holes at random (inside, crossing, outside,
// touching), several polygons (apart, overlapping, islands in holes), and
// spikes, wrong orientation, repeated points.
TEST(ClearValidity, WhatItAcceptsBoostAccepts) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto ring_around = [&](double cx, double cy, double r, int n, bool star, bool clockwise) {
    std::vector<double> angles(n);
    for (int i = 0; i < n; ++i) angles[i] = 2 * M_PI * (star ? (i + 0.8 * u(rng)) / n : u(rng));
    Ring ring;
    for (int i = 0; i < n; ++i) {
      const double a = clockwise ? -angles[i] : angles[i];
      const double rr = r * (0.5 + 0.5 * u(rng));
      ring.push_back(Point(cx + rr * std::cos(a), cy + rr * std::sin(a)));
    }
    // Sometimes a vertex exactly on another edge, a spike or a repeated point.
    const double roll = u(rng);
    if (roll < 0.05 && n > 3) ring[2] = Point(0.5 * (ring[0].x() + ring[1].x()), 0.5 * (ring[0].y() + ring[1].y()));
    else if (roll < 0.10 && n > 3) ring[2] = ring[0];
    else if (roll < 0.15) ring.insert(ring.begin() + 1, ring[1]);
    ring.push_back(ring.front());
    return ring;
  };
  int accepted = 0, boost_valid = 0, stars_accepted = 0, stars = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    TypedMultiPolygon polygons;
    const int count = 1 + static_cast<int>(3 * u(rng));
    const bool star = u(rng) < 0.7;
    for (int k = 0; k < count; ++k) {
      TypedPolygon p;
      const double cx = 10 * u(rng), cy = 10 * u(rng), r = 1 + 4 * u(rng);
      p.geometry.outer() = ring_around(cx, cy, r, 3 + static_cast<int>(12 * u(rng)), star, u(rng) < 0.05);
      const int holes = static_cast<int>(3 * u(rng));
      for (int h = 0; h < holes; ++h)
        p.geometry.inners().push_back(ring_around(cx + r * (u(rng) - 0.5), cy + r * (u(rng) - 0.5),
                                                  0.05 + 0.4 * r * u(rng), 3 + static_cast<int>(6 * u(rng)), true,
                                                  u(rng) < 0.95));
      for (const auto* ring = &p.geometry.outer(); ring; ring = nullptr)
        p.edge_types.push_back(std::vector<EdgeType>(ring->size() - 1, E::kObstacle));
      for (const auto& inner : p.geometry.inners()) p.edge_types.push_back(std::vector<EdgeType>(inner.size() - 1, E::kFrontier));
      polygons.push_back(std::move(p));
    }
    const bool clear = is_clearly_valid(polygons);
    const bool valid = bg::is_valid(geometry_of(polygons));
    if (clear) ++accepted;
    if (valid) ++boost_valid;
    if (star && count == 1 && polygons[0].geometry.inners().empty()) {
      ++stars;
      stars_accepted += clear ? 1 : 0;
    }
    ASSERT_TRUE(!clear || valid) << "trial " << trial << ": accepted, but Boost says invalid: "
                                 << bg::wkt(geometry_of(polygons));
  }
  std::printf("clearly valid %d, Boost valid %d of 4000; simple star rings accepted %d of %d\n", accepted,
              boost_valid, stars_accepted, stars);
  // It must also be useful: most valid inputs are shown valid without Boost.
  EXPECT_GT(accepted, boost_valid * 3 / 4);
}

// Rings that touch at a point are valid for Boost but not "clearly" valid:
// they are left to Boost. Islands in holes are clearly valid.
TEST(ClearValidity, TouchingRingsAreLeftToBoost) {
  // A hole touching the outer ring at one point: valid for Boost, "not shown" here.
  TypedPolygon p = make({{0, 0}, {4, 0}, {4, 4}, {0, 4}}, {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle});
  p.geometry.inners().push_back(Ring{{0, 2}, {1, 3}, {1, 1}, {0, 2}});
  p.edge_types.push_back({E::kObstacle, E::kObstacle, E::kObstacle});
  EXPECT_TRUE(bg::is_valid(p.geometry));
  EXPECT_FALSE(is_clearly_valid(TypedMultiPolygon{p}));
  // The same hole moved off the outer ring is clearly valid.
  p.geometry.inners()[0] = Ring{{0.5, 2}, {1, 3}, {1, 1}, {0.5, 2}};
  EXPECT_TRUE(is_clearly_valid(TypedMultiPolygon{p}));
  // An island inside that hole is fine; one across the hole's edge is not.
  TypedPolygon island = make({{0.8, 1.8}, {0.9, 1.8}, {0.9, 2.2}, {0.8, 2.2}}, {E::kFrontier, E::kFrontier, E::kFrontier, E::kFrontier});
  EXPECT_TRUE(is_clearly_valid(TypedMultiPolygon{p, island}));
  TypedPolygon across = make({{2, 2}, {3, 2}, {3, 3}, {2, 3}}, {E::kFrontier, E::kFrontier, E::kFrontier, E::kFrontier});
  EXPECT_FALSE(is_clearly_valid(TypedMultiPolygon{p, across}));  // inside p, not in a hole: overlaps it
}

}  // namespace
// Boost's is_valid merges features below about 1e-7 of the geometry's box
// (its rescaling): a notch of a few nanometres at a vertex is a spike to it.
// Such a polygon is left to Boost, at any place and size of the box; a notch
// of a micrometre is clearly valid (what the float end points of scans make
// every insert, which must not all go to Boost).
TEST(ClearValidity, AFeatureBoostMergesIsLeftToBoost) {
  auto notched = [](double offset_m, double box_m, double notch_m) {
    // A triangle-like ring with a V at its bottom vertex: two edges of
    // notch_m at 70 degrees between them.
    const double half = 0.5 * (M_PI - 70.0 * M_PI / 180.0);
    const Point v(offset_m + 2.0, offset_m);
    const Point a(offset_m + 2.0 - notch_m * std::cos(half), offset_m + notch_m * std::sin(half));
    const Point b(offset_m + 2.0 + notch_m * std::cos(half), offset_m + notch_m * std::sin(half));
    return make({v, b, {offset_m + 3.0 + box_m, offset_m + 2.0 + box_m}, {offset_m + 1.0 - box_m, offset_m + 2.0 + box_m}, a},
                std::vector<EdgeType>(5, E::kObstacle));
  };
  for (const double offset : {0.0, 1000.0}) {
    for (const double box : {0.0, 100.0}) {
      const TypedMultiPolygon nano{notched(offset, box, 2e-9)};
      EXPECT_FALSE(bg::is_valid(geometry_of(nano))) << offset << " " << box;
      EXPECT_FALSE(is_clearly_valid(nano)) << offset << " " << box;
    }
    const TypedMultiPolygon micro{notched(offset, 0.0, 1e-6)};
    EXPECT_TRUE(bg::is_valid(geometry_of(micro)));
    EXPECT_TRUE(is_clearly_valid(micro)) << offset;
  }
}

}  // namespace pex::mapping
