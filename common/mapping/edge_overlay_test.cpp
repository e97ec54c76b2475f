#include "mapping/edge_overlay.hpp"

#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mapping/scan_polygon.hpp"
#include "mapping/test_support.hpp"

namespace pex::mapping {
namespace {

using geometry::Pose2;

using E = EdgeType;

TypedPolygon rect(double x0, double y0, double x1, double y1, EdgeType type = E::kFrontier) {
  TypedPolygon p;
  p.geometry.outer() = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, {x0, y0}};
  p.edge_types.push_back(std::vector<EdgeType>(4, type));
  return p;
}

void add_hole(TypedPolygon& p, double x0, double y0, double x1, double y1, EdgeType type = E::kObstacle) {
  p.geometry.inners().push_back(Ring{{x0, y0}, {x0, y1}, {x1, y1}, {x1, y0}, {x0, y0}});  // clockwise
  p.edge_types.push_back(std::vector<EdgeType>(4, type));
}

// The oracle: Boost.Geometry's union or intersection of the same geometry.
MultiPolygon boost_overlay(const TypedMultiPolygon& a, const TypedMultiPolygon& b, OverlayOp op) {
  MultiPolygon out;
  switch (op) {
    case OverlayOp::kUnion: bg::union_(geometry_of(a), geometry_of(b), out); break;
    case OverlayOp::kIntersection: bg::intersection(geometry_of(a), geometry_of(b), out); break;
    case OverlayOp::kDifference: bg::difference(geometry_of(a), geometry_of(b), out); break;
  }
  return out;
}

double boundary_distance(const Point& p, const MultiPolygon& polygons) {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& polygon : polygons) {
    d = std::min(d, static_cast<double>(bg::distance(p, polygon.outer())));
    for (const auto& inner : polygon.inners()) d = std::min(d, static_cast<double>(bg::distance(p, inner)));
  }
  return d;
}

// The result is valid, is the oracle's point set (symmetric difference of no
// area) and every edge lies on an input edge of its type.
void expect_matches_boost(const TypedMultiPolygon& a, const TypedMultiPolygon& b, OverlayOp op,
                          const OverlayResult& r) {
  ASSERT_TRUE(r.ok) << r.error;
  std::string why;
  ASSERT_TRUE(is_valid(r.polygons, &why)) << why;
  const MultiPolygon expected = boost_overlay(a, b, op);
  // The overlay rounds every point onto its grid, moving the boundary by at
  // most kOverlayMovesM: an area by at most the boundary's length times that.
  const double scale = std::max(1.0, bg::area(expected));
  const double boundary_m = bg::perimeter(geometry_of(a)) + bg::perimeter(geometry_of(b));
  EXPECT_NEAR(area(r.polygons), bg::area(expected), 1e-9 * scale + boundary_m * kOverlayMovesM);
  // Same point set: sampled points are inside both or outside both, but for
  // points on a boundary. (Boost's sym_difference of two equal inputs is not
  // reliable enough to be the oracle here.)
  const MultiPolygon ours = geometry_of(r.polygons);
  Box envelope;
  bg::envelope(expected, envelope);
  if (!ours.empty()) bg::expand(envelope, bg::return_envelope<Box>(ours));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(envelope.min_corner().x(), envelope.max_corner().x());
  std::uniform_real_distribution<double> uy(envelope.min_corner().y(), envelope.max_corner().y());
  int disagreements = 0;
  for (int k = 0; k < (expected.empty() ? 0 : 2000); ++k) {
    const Point s(ux(rng), uy(rng));
    if (bg::covered_by(s, ours) != bg::covered_by(s, expected) &&
        boundary_distance(s, expected) > kOverlayMovesM)
      ++disagreements;
  }
  EXPECT_EQ(disagreements, 0) << "op " << int(op) << "\nours " << bg::wkt(ours) << "\nboost " << bg::wkt(expected);
  for_each_edge(r.polygons, [&](const Point& p, const Point& q, EdgeType t) {
    bool found = false;
    auto look = [&](const Point& u, const Point& v, EdgeType s) {
      const Segment source(u, v);
      if (s == t && bg::distance(p, source) < kOverlayMovesM && bg::distance(q, source) < kOverlayMovesM) found = true;
    };
    for_each_edge(a, look);
    for_each_edge(b, look);
    EXPECT_TRUE(found) << "edge " << bg::wkt(p) << " " << bg::wkt(q) << " typed " << to_string(t)
                       << " lies on no input edge of that type";
  });
}

TEST(EdgeOverlay, OverlappingRectanglesKeepTheirEdgeTypes) {
  const TypedMultiPolygon a{rect(0, 0, 4, 4, E::kObstacle)}, b{rect(2, 1, 6, 3, E::kFrontier)};
  const auto u = overlay(a, b, OverlayOp::kUnion);
  expect_matches_boost(a, b, OverlayOp::kUnion, u);
  EXPECT_NEAR(edge_length(u.polygons, E::kObstacle), 16.0 - 2.0, 1e-12);
  EXPECT_NEAR(edge_length(u.polygons, E::kFrontier), 2 + 2 + 2, 1e-12);
  const auto i = overlay(a, b, OverlayOp::kIntersection);
  expect_matches_boost(a, b, OverlayOp::kIntersection, i);
  EXPECT_NEAR(area(i.polygons), 4.0, 1e-12);
}

// Tiles and their pieces share whole edges along tile borders: pieces that
// overlap in the same direction are kept once, in opposite directions dropped.
TEST(EdgeOverlay, SharedAndOverlappingEdges) {
  const TypedMultiPolygon left{rect(0, 0, 2, 2)}, right{rect(2, 0, 4, 2, E::kObstacle)};
  const auto side_by_side = overlay(left, right, OverlayOp::kUnion);
  expect_matches_boost(left, right, OverlayOp::kUnion, side_by_side);
  ASSERT_EQ(side_by_side.polygons.size(), 1u);
  const TypedMultiPolygon lower{rect(0, 0, 4, 2)}, taller{rect(1, 0, 3, 3, E::kObstacle)};
  const auto same_base = overlay(lower, taller, OverlayOp::kUnion);  // bottoms overlap, same direction
  expect_matches_boost(lower, taller, OverlayOp::kUnion, same_base);
  // The shared bottom piece (1..3) is kept once, with the more specific type.
  EXPECT_NEAR(edge_length(same_base.polygons, E::kObstacle), 2 + 1 + 2 + 1, 1e-12);
  const auto itself = overlay(lower, lower, OverlayOp::kUnion);
  expect_matches_boost(lower, lower, OverlayOp::kUnion, itself);
  EXPECT_EQ(vertex_count(itself.polygons), 4u);
  const auto clip = overlay(taller, lower, OverlayOp::kIntersection);
  expect_matches_boost(taller, lower, OverlayOp::kIntersection, clip);
}

TEST(EdgeOverlay, RingsThatTouchAtAPointStaySeparate) {
  const TypedMultiPolygon a{rect(0, 0, 1, 1)}, b{rect(1, 1, 2, 2)};
  const auto r = overlay(a, b, OverlayOp::kUnion);
  expect_matches_boost(a, b, OverlayOp::kUnion, r);
  EXPECT_EQ(r.polygons.size(), 2u);
}

// Filling a courtyard but for two squares that touch at its centre leaves two
// holes touching at a point: two rings (one ring through the point twice is
// not valid), and so for a hole that touches the outer ring.
TEST(EdgeOverlay, HolesThatTouchAtAPointAreSeparateRings) {
  TypedPolygon room = rect(0, 0, 4, 4);
  add_hole(room, 1, 1, 3, 3);
  const TypedMultiPolygon a{room}, b{rect(1, 2, 2, 3, E::kObstacle), rect(2, 1, 3, 2, E::kObstacle)};
  const auto r = overlay(a, b, OverlayOp::kUnion);
  expect_matches_boost(a, b, OverlayOp::kUnion, r);
  ASSERT_EQ(r.polygons.size(), 1u);
  EXPECT_EQ(r.polygons[0].geometry.inners().size(), 2u);
  EXPECT_NEAR(area(r.polygons), 16.0 - 2.0, 1e-12);
  // A C-shaped room whose mouth a bar closes, touching the lower arm's end
  // at one point: the mouth becomes a hole that touches the outer ring there.
  TypedPolygon c;
  c.geometry.outer() = {{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 2}, {3, 2}, {3, 3}, {0, 3}, {0, 0}};
  c.edge_types.push_back(std::vector<EdgeType>(8, E::kFrontier));
  TypedPolygon bar;  // from (3, 1) up the mouth to the upper arm, overlapping it
  bar.geometry.outer() = {{3, 1}, {4, 1}, {4, 2.5}, {2.5, 2.5}, {2.5, 2}, {3, 2}, {3, 1}};
  bar.edge_types.push_back(std::vector<EdgeType>(6, E::kObstacle));
  const TypedMultiPolygon cee{c}, closing{bar};
  const auto closed = overlay(cee, closing, OverlayOp::kUnion);
  expect_matches_boost(cee, closing, OverlayOp::kUnion, closed);
  ASSERT_EQ(closed.polygons.size(), 1u);
  EXPECT_EQ(closed.polygons[0].geometry.inners().size(), 1u);
}

TEST(EdgeOverlay, HolesIslandsAndContainment) {
  TypedPolygon room = rect(0, 0, 10, 10);
  add_hole(room, 2, 2, 4, 4);
  add_hole(room, 6, 6, 8, 8);
  const TypedMultiPolygon a{room};
  // b fills one hole exactly, overlaps the other, and has a hole of its own.
  TypedPolygon patch = rect(5, 5, 9, 9);
  add_hole(patch, 5.5, 5.5, 5.8, 5.8);
  const TypedMultiPolygon b{rect(2, 2, 4, 4, E::kObstacle), patch};
  expect_matches_boost(a, b, OverlayOp::kUnion, overlay(a, b, OverlayOp::kUnion));
  expect_matches_boost(a, b, OverlayOp::kIntersection, overlay(a, b, OverlayOp::kIntersection));
  // An island inside a hole stays an island; b inside a's interior changes nothing.
  const TypedMultiPolygon island{rect(2.5, 2.5, 3.5, 3.5)}, inner{rect(1, 5, 2, 6)};
  const auto with_island = overlay(a, island, OverlayOp::kUnion);
  expect_matches_boost(a, island, OverlayOp::kUnion, with_island);
  EXPECT_EQ(with_island.polygons.size(), 2u);
  const auto unchanged = overlay(a, inner, OverlayOp::kUnion);
  expect_matches_boost(a, inner, OverlayOp::kUnion, unchanged);
  EXPECT_EQ(vertex_count(unchanged.polygons), vertex_count(a));
  const TypedMultiPolygon none;
  EXPECT_NEAR(area(overlay(a, none, OverlayOp::kUnion).polygons), area(a), 1e-12);
  EXPECT_TRUE(overlay(a, none, OverlayOp::kIntersection).polygons.empty());
}

// The planning map's difference: a room minus a band along two of its walls
// (one band edge on the wall itself, in the opposite direction) and a pillar.
TEST(EdgeOverlay, DifferenceTakesTheSubtrahendsEdgesTurnedRound) {
  const TypedMultiPolygon room{rect(0, 0, 10, 6, E::kFrontier)};
  TypedMultiPolygon obstacles{rect(-0.1, -0.1, 10.1, 0.02, E::kObstacle), rect(4, 2, 5, 3, E::kObstacle)};
  const auto r = overlay(room, obstacles, OverlayOp::kDifference);
  expect_matches_boost(room, obstacles, OverlayOp::kDifference, r);
  // y = 0.02 is not on the overlay's grid: the band's side moves onto it.
  const double moved_area = (bg::perimeter(geometry_of(room)) + bg::perimeter(geometry_of(obstacles))) * kOverlayMovesM;
  EXPECT_NEAR(area(r.polygons), 60.0 - 10 * 0.02 - 1.0, moved_area);
  EXPECT_NEAR(edge_length(r.polygons, E::kObstacle), 10.0 + 4.0, 2 * 5 * kOverlayMovesM);  // band's inner side, pillar
  EXPECT_NEAR(edge_length(r.polygons, E::kFrontier), 10.0 + 2 * (6 - 0.02), 2 * 3 * kOverlayMovesM);
  // A band edge lying on a room edge in the opposite direction bounds the
  // difference: the room's top (x 0..10 at y 6) against a band whose bottom is y 6.
  const TypedMultiPolygon cap{rect(2, 6, 8, 6.1, E::kObstacle)};
  const auto capped = overlay(room, cap, OverlayOp::kDifference);
  expect_matches_boost(room, cap, OverlayOp::kDifference, capped);
  EXPECT_NEAR(edge_length(capped.polygons, E::kObstacle), 6.0, 1e-9);  // the shared piece: the more specific type
  // The side types replace the operands' own (free edges frontier, band edges obstacle).
  std::vector<RingRef> a_rings, b_rings;
  add_rings(room, a_rings);
  const TypedMultiPolygon pillar{rect(4, 2, 5, 3, E::kFrontier)};
  add_rings(pillar, b_rings);
  const auto typed = overlay(a_rings, b_rings, OverlayOp::kDifference, std::nullopt, {E::kFrontier, E::kObstacle});
  ASSERT_TRUE(typed.ok) << typed.error;
  EXPECT_NEAR(edge_length(typed.polygons, E::kObstacle), 4.0, 1e-12);
}

TEST(EdgeOverlay, BorderBoxSidesAreTypedBorder) {
  const TypedMultiPolygon scan{rect(-1, 1, 3, 2, E::kObstacle)};
  const Box box(Point(0, 0), Point(8, 8));
  TypedMultiPolygon tile{rect(0, 0, 8, 8, E::kBorder)};
  const auto r = overlay(scan, tile, OverlayOp::kIntersection, box);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NEAR(area(r.polygons), 3.0, 1e-12);
  EXPECT_NEAR(edge_length(r.polygons, E::kBorder), 1.0, 1e-12);
  EXPECT_NEAR(edge_length(r.polygons, E::kObstacle), 7.0, 1e-12);
}

// Real shapes: unions of scan polygons in random rooms (many vertices, near
// parallel walls, shared end points) against Boost, their pieces in random
// boxes, and the maps minus random rectangles.
TEST(EdgeOverlay, RandomScanMapsAgreeWithBoost) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const testing::ScanSpec spec;
  ScanPolygonOptions options;
  options.range_max_m = spec.range_max_m;
  int cases = 0, failed = 0;
  for (int room = 0; room < 6; ++room) {
    const auto walls = testing::random_room(20, 14, 15, rng);
    TypedMultiPolygon map;
    for (int k = 0; k < 40; ++k) {
      const Pose2 pose{2 + 16 * u(rng), 2 + 10 * u(rng), 6.28 * u(rng)};
      const auto scan = scan_to_polygon(testing::cast_scan(walls, pose, spec, 0.01, &rng), spec.angle_min,
                                        spec.angle_increment, pose, options);
      ASSERT_TRUE(scan.ok) << scan.error;
      const TypedMultiPolygon b{scan.polygon};
      const auto r = overlay(map, b, OverlayOp::kUnion);
      ++cases;
      if (!r.ok) {
        ++failed;
        continue;
      }
      expect_matches_boost(map, b, OverlayOp::kUnion, r);
      if (::testing::Test::HasFailure()) return;
      const double x = 20 * u(rng), y = 14 * u(rng);
      const TypedMultiPolygon box{rect(x - 3, y - 3, x + 3, y + 3, E::kBorder)};
      const auto clip = overlay(r.polygons, box, OverlayOp::kIntersection);
      ++cases;
      if (!clip.ok) {
        ++failed;
        continue;
      }
      expect_matches_boost(r.polygons, box, OverlayOp::kIntersection, clip);
      if (::testing::Test::HasFailure()) return;
      // A pillar-sized band cut out of the map (the planning map's difference).
      const TypedMultiPolygon cut{rect(x - 0.5, y - 0.3, x + 0.5, y + 0.3, E::kObstacle)};
      const auto difference = overlay(r.polygons, cut, OverlayOp::kDifference);
      ++cases;
      if (!difference.ok) {
        ++failed;
        continue;
      }
      expect_matches_boost(r.polygons, cut, OverlayOp::kDifference, difference);
      if (::testing::Test::HasFailure()) return;
      map = r.polygons;
    }
  }
  EXPECT_EQ(cases, 720);
  EXPECT_EQ(failed, 0);
}

// Coordinates the grid cannot hold (beyond kOverlayMaxCoordinateM, or not
// finite) are refused with the reason, not rounded into a wrong map.
TEST(EdgeOverlay, CoordinatesBeyondTheGridAreRefusedWithTheReason) {
  const TypedMultiPolygon room{rect(0, 0, 4, 4)};
  const TypedMultiPolygon near_edge{rect(kOverlayMaxCoordinateM - 2, 0, kOverlayMaxCoordinateM, 1)};
  EXPECT_TRUE(overlay(room, near_edge, OverlayOp::kUnion).ok);
  const TypedMultiPolygon far{rect(1e5, 0, 1e5 + 1, 1)};
  TypedMultiPolygon not_finite{rect(1, 1, 2, 2)};
  not_finite[0].geometry.outer()[1] = Point(std::numeric_limits<double>::quiet_NaN(), 1);
  for (const TypedMultiPolygon* bad : {&far, static_cast<const TypedMultiPolygon*>(&not_finite)}) {
    const auto r = overlay(room, *bad, OverlayOp::kUnion);
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.error.find("not finite or beyond 8192 m"), std::string::npos) << r.error;
    EXPECT_TRUE(r.polygons.empty());
  }
}

// Operands made to be near-degenerate: lattice shapes and the same shapes
// moved by 1e-9 m to 1e-5 m (below, at and above the overlay's grid), or
// turned by as many radians, so their edges nearly coincide, nearly touch
// and cross at tiny angles everywhere. Every overlay
// must succeed with a valid result whose areas agree with each other
// (union + intersection = a + b, difference = a - intersection) up to the
// rounding's bound: no oracle, whose own robustness such inputs test.
TEST(EdgeOverlay, NearDegenerateOperandsAlwaysOverlay) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> lattice(0, 16);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const EdgeType kinds[3] = {E::kObstacle, E::kFrontier, E::kBorder};
  auto typed = [&](const MultiPolygon& geometry) {
    TypedMultiPolygon out;
    for (const auto& g : geometry) {
      TypedPolygon p{g, {}};
      p.edge_types.emplace_back(g.outer().size() - 1, kinds[rng() % 3]);
      for (const auto& inner : g.inners()) p.edge_types.emplace_back(inner.size() - 1, kinds[rng() % 3]);
      out.push_back(std::move(p));
    }
    return out;
  };
  // A union of lattice rectangles and right triangles, 0.25 m apart.
  auto lattice_shape = [&] {
    MultiPolygon shape;
    for (int k = 0; k < 6; ++k) {
      const double x0 = 0.25 * lattice(rng), y0 = 0.25 * lattice(rng);
      const double w = 0.25 * (1 + lattice(rng) % 6), h = 0.25 * (1 + lattice(rng) % 6);
      Polygon part;
      if (k % 2 == 0) {
        part.outer() = {{x0, y0}, {x0 + w, y0}, {x0 + w, y0 + h}, {x0, y0 + h}, {x0, y0}};
      } else {
        part.outer() = {{x0, y0}, {x0 + w, y0}, {x0, y0 + h}, {x0, y0}};
      }
      MultiPolygon grown;
      bg::union_(shape, part, grown);
      shape = std::move(grown);
    }
    return shape;
  };
  auto moved = [](const MultiPolygon& shape, double dx, double dy, double turn_rad) {
    MultiPolygon out = shape;
    const double c = std::cos(turn_rad), s = std::sin(turn_rad);
    auto move = [&](Point& p) { p = Point(c * p.x() - s * p.y() + dx, s * p.x() + c * p.y() + dy); };
    for (auto& polygon : out) {
      for (auto& p : polygon.outer()) move(p);
      for (auto& inner : polygon.inners())
        for (auto& p : inner) move(p);
    }
    return out;
  };
  const double scales[5] = {1e-9, 1e-7, 0.5 * kOverlayGridM, 2e-6, 1e-5};
  int cases = 0;
  for (int trial = 0; trial < 10000; ++trial) {
    const MultiPolygon shape = lattice_shape();
    const double scale = scales[trial % 5];
    MultiPolygon other;
    switch (trial / 5 % 3) {
      case 0: other = moved(shape, scale * u(rng), scale * u(rng), 0.0); break;
      case 1: other = moved(shape, 0.0, 0.0, scale * u(rng)); break;
      case 2: other = moved(lattice_shape(), scale * u(rng), scale * u(rng), 0.0); break;
    }
    const TypedMultiPolygon a = typed(shape), b = typed(other);
    if (!is_valid(a) || !is_valid(b)) continue;  // an operand Boost calls invalid: outside the contract
    ++cases;
    const auto united = overlay(a, b, OverlayOp::kUnion);
    const auto common = overlay(a, b, OverlayOp::kIntersection);
    const auto less = overlay(a, b, OverlayOp::kDifference);
    for (const auto* r : {&united, &common, &less}) {
      ASSERT_TRUE(r->ok) << r->error << " trial " << trial << "\na " << bg::wkt(shape) << "\nb " << bg::wkt(other);
      std::string why;
      ASSERT_TRUE(is_valid(r->polygons, &why)) << why << " trial " << trial << "\na " << bg::wkt(shape) << "\nb "
                                               << bg::wkt(other) << "\nout " << bg::wkt(geometry_of(r->polygons));
    }
    const double moved_area = (bg::perimeter(shape) + bg::perimeter(other)) * kOverlayMovesM;
    EXPECT_NEAR(area(united.polygons) + area(common.polygons), area(a) + area(b), 2 * moved_area) << trial;
    EXPECT_NEAR(area(less.polygons), area(a) - area(common.polygons), 2 * moved_area) << trial;
  }
  EXPECT_GT(cases, 9000);
}

}  // namespace
}  // namespace pex::mapping
