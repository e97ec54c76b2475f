#include "planning/cspace.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numbers>
#include <random>

#include "mapping/polygon_map.hpp"
#include "mapping/test_support.hpp"
#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

using testing::rectangle;
using testing::rectangle_hole;
using testing::typed_polygon;
using testing::disk;
using testing::RingSpec;


TEST(ConfigurationSpace, SquareRoomShrinksByTheRadius) {
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10))}, disk(0.5)).ok);
  ASSERT_EQ(cs.polygons().size(), 1u);
  // The offset is exact up to its 10 um grid.
  EXPECT_NEAR(mapping::area(cs.polygons()), 9.0 * 9.0, 1e-4);
  EXPECT_TRUE(cs.covers(Point(5, 5)));
  EXPECT_TRUE(cs.covers(Point(0.6, 9.4)));
  EXPECT_FALSE(cs.covers(Point(0.4, 5)));
  EXPECT_NEAR(cs.distance_to_boundary(Point(5, 5)), 4.5, 1e-5);
  EXPECT_TRUE(cs.segment_free(Point(1, 1), Point(9, 9)));
  EXPECT_FALSE(cs.segment_free(Point(5, 5), Point(5, 9.7)));
  // A convex room has no reflex vertex: no node to bend around.
  EXPECT_TRUE(cs.reflex_nodes().empty());
}

TEST(ConfigurationSpace, EdgeTypesSurviveTheOffset) {
  using E = EdgeType;
  ConfigurationSpace cs;
  CSpaceOptions typed = disk(0.5);
  typed.edge_types = true;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 4, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))},
                       typed)
                  .ok);
  int frontier_edges = 0;
  for (const auto& e : cs.edges()) {
    const bool on_right_side = std::abs(e.a.x() - 9.5) < 1e-6 && std::abs(e.b.x() - 9.5) < 1e-6;
    EXPECT_EQ(e.type == E::kFrontier, on_right_side) << e.a.x() << "," << e.a.y();
    frontier_edges += e.type == E::kFrontier ? 1 : 0;
  }
  EXPECT_EQ(frontier_edges, 1);
}

TEST(ConfigurationSpace, PillarGivesReflexNodesOutsideItsClearance) {
  ConfigurationSpace cs;
  const double r = 0.3;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10), {rectangle_hole(4, 4, 6, 6)})}, disk(r)).ok);
  ASSERT_FALSE(cs.reflex_nodes().empty());
  const std::vector<Point> pillar{Point(4, 4), Point(6, 4), Point(6, 6), Point(4, 6)};
  for (const auto& node : cs.reflex_nodes()) {
    EXPECT_TRUE(cs.covers(node));
    // Nodes lie on the round joins around the pillar's corners, just inside.
    EXPECT_GE(testing::distance_to_ring(node, pillar), r - 1e-6);
    EXPECT_LE(testing::distance_to_ring(node, pillar), r + 0.01);
    EXPECT_GT(cs.distance_to_boundary(node), 0.0);
  }
  EXPECT_FALSE(cs.segment_free(Point(2, 5), Point(8, 5)));  // through the pillar
  EXPECT_TRUE(cs.segment_free(Point(2, 2), Point(8, 2)));
}

TEST(ConfigurationSpace, NearestInteriorPointMovesAFrontierPointInside) {
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10))}, disk(0.5)).ok);
  const auto q = cs.nearest_interior_point(Point(10, 5), 1.0);
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR(q->x(), 9.5, 2e-3);
  EXPECT_NEAR(q->y(), 5.0, 1e-5);
  EXPECT_TRUE(cs.covers(*q));
  EXPECT_GT(cs.distance_to_boundary(*q), 0.0);
  // From beyond a corner: the corner vertex, moved in along its bisector.
  const auto corner = cs.nearest_interior_point(Point(10.2, 10.2), 2.0);
  ASSERT_TRUE(corner.has_value());
  EXPECT_LT(corner->x(), 9.5);
  EXPECT_LT(corner->y(), 9.5);
  EXPECT_NEAR(corner->x(), 9.5, 3e-3);
  // Too far away, and a non-finite point: none.
  EXPECT_FALSE(cs.nearest_interior_point(Point(12, 5), 1.0).has_value());
  EXPECT_FALSE(cs.nearest_interior_point(Point(std::nan(""), 5), 1.0).has_value());
  // A point well inside is its own answer.
  const auto inside = cs.nearest_interior_point(Point(3, 3), 1.0);
  ASSERT_TRUE(inside.has_value());
  EXPECT_EQ(inside->x(), 3.0);
}

// A strip of map just wider than the robot gives a piece of C-space thinner
// than interior_offset_m: its boundary is nearest the point, and no interior
// lies beside it. The answer is then the nearest boundary point that has
// interior beside it, here the room's, in place of none (session 45: such a
// sliver left a frontier "with no C-space near" on intel).
TEST(ConfigurationSpace, NearestInteriorPointLooksPastASliverWithNoInterior) {
  CSpaceOptions o = disk(0.27);
  o.simplify_epsilon_m = 0.0;
  ConfigurationSpace cs;
  const auto built =
      cs.build({typed_polygon(rectangle(0, 0, 4, 4)), typed_polygon(rectangle(6, 0, 9, 0.5404))}, o);
  ASSERT_TRUE(built.ok) << built.error;
  ASSERT_EQ(cs.polygons().size(), 2u);  // the sliver is a piece of its own
  const Point p(7.5, 0.6);
  ASSERT_LT(cs.distance_to_boundary(p), 0.34);  // the sliver's edge, 0.33 m away
  const auto q = cs.nearest_interior_point(p, 5.0);
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR(q->x(), 3.73, 2e-3);
  EXPECT_NEAR(q->y(), 0.6, 1e-3);
  EXPECT_TRUE(cs.covers(*q));
  EXPECT_GT(cs.distance_to_boundary(*q), 0.5 * o.interior_offset_m);
  // Within a range that holds the sliver only: none.
  EXPECT_FALSE(cs.nearest_interior_point(p, 1.0).has_value());
}

TEST(ConfigurationSpace, CorridorNarrowerThanTheRobotIsEmpty) {
  ConfigurationSpace cs;
  const auto built = cs.build({typed_polygon(rectangle(0, 0, 10, 0.4))}, disk(0.25));
  ASSERT_TRUE(built.ok) << built.error;
  EXPECT_TRUE(cs.empty());
  EXPECT_FALSE(cs.covers(Point(5, 0.2)));
  EXPECT_FALSE(cs.nearest_interior_point(Point(5, 0.2), 1.0).has_value());
}

TEST(ConfigurationSpace, RejectsTypesThatDoNotMatchTheRings) {
  auto polygon = typed_polygon(rectangle(0, 0, 10, 10));
  polygon.edge_types[0].pop_back();
  ConfigurationSpace cs;
  const auto built = cs.build({polygon}, disk(0.25));
  EXPECT_FALSE(built.ok);
  EXPECT_FALSE(built.error.empty());
}

TEST(SegmentsIntersect, ProperTouchingAndDisjoint) {
  EXPECT_TRUE(segments_intersect(Point(0, 0), Point(2, 2), Point(0, 2), Point(2, 0)));
  EXPECT_TRUE(segments_intersect(Point(0, 0), Point(2, 0), Point(1, 0), Point(1, 1)));  // T touch
  EXPECT_TRUE(segments_intersect(Point(0, 0), Point(2, 0), Point(1, 0), Point(3, 0)));  // overlap
  EXPECT_FALSE(segments_intersect(Point(0, 0), Point(2, 0), Point(3, 0), Point(4, 0)));  // collinear apart
  EXPECT_FALSE(segments_intersect(Point(0, 0), Point(2, 0), Point(0, 1), Point(2, 1)));
}

// Maps like the mapper's: a world of walls scanned with range noise along a
// random walk and put together by a PolygonMap (ragged walls, frontiers,
// clutter), planning layer merged.
TypedMultiPolygon scanned_map(const std::vector<mapping::testing::Wall>& walls, double w, double h, int scans,
                              std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> step(-1.0, 1.0), turn(-0.6, 0.6);
  mapping::PolygonMap map;
  mapping::ScanPolygonOptions scan_options;
  scan_options.range_max_m = 10.0;
  geometry::Pose2 pose{1.5, 1.5, 0.5};
  for (int k = 0; k < scans; ++k) {
    const auto ranges = mapping::testing::cast_scan(walls, pose, mapping::testing::ScanSpec{}, 0.012, &rng);
    const auto scan = mapping::scan_to_polygon(ranges, -3.0 * std::numbers::pi / 4.0, std::numbers::pi / 360.0,
                                               pose, scan_options);
    if (scan.ok) map.insert(scan.polygon);
    const double x = std::clamp(pose.x_m + step(rng), 1.0, w - 1.0), y = std::clamp(pose.y_m + step(rng), 1.0, h - 1.0);
    if (mapping::testing::cast_ray(walls, pose.x_m, pose.y_m, std::atan2(y - pose.y_m, x - pose.x_m)) >
        std::hypot(x - pose.x_m, y - pose.y_m) + 0.5) {
      pose.x_m = x;
      pose.y_m = y;
    }
    pose.theta_rad += turn(rng);
  }
  auto merged = map.planning_map();
  EXPECT_TRUE(merged.ok) << merged.error;
  return merged.polygons;
}

std::vector<TypedMultiPolygon> oracle_maps() {
  std::vector<TypedMultiPolygon> maps;
  std::mt19937_64 rng(17);
  for (int k = 0; k < 3; ++k) maps.push_back(scanned_map(mapping::testing::random_room(14, 10, 8, rng), 14, 10, 40, 100 + k));
  maps.push_back(scanned_map(mapping::testing::rock_field(12, 12, 2.0, rng), 12, 12, 40, 7));
  // Several polygons (the C-space is offset polygon by polygon): two rooms
  // touching at a corner, one with a pillar, and a third room apart.
  maps.push_back({typed_polygon(rectangle(0, 0, 5, 4)), typed_polygon(rectangle(5, 4, 9, 8), {rectangle_hole(6, 5, 7, 6)}),
                  typed_polygon(rectangle(10, 0, 14, 3))});
  // Hand-drawn: two halls joined by a 0.8 m wide, 3 m long passage; a pillar.
  maps.push_back({typed_polygon(
      RingSpec{{Point(0, 0), Point(12, 0), Point(12, 3), Point(7.4, 3), Point(7.4, 6), Point(12, 6), Point(12, 9),
                Point(0, 9), Point(0, 6), Point(6.6, 6), Point(6.6, 3), Point(0, 3)}, {}},
      {rectangle_hole(3, 1.3, 3.4, 1.7)})});
  return maps;  // the hand-drawn halls last (ClipperOffsetKeepsAPassageTheRobotFitsThroughOpen)
}

double min_distance_to_edges(const Point& p, const TypedMultiPolygon& map) {
  double best = std::numeric_limits<double>::infinity();
  mapping::for_each_edge(map, [&](const Point& a, const Point& b, EdgeType) {
    best = std::min(best, distance(p, closest_point_on_segment(p, a, b)));
  });
  return best;
}

// Our offset (Clipper) against the reference (Boost.Geometry's buffer, the
// C-space before): the same set up to where the round joins put their
// vertices, the same connected pieces, and every C-space vertex at least the
// clearance the docs promise from every map edge and inside the map. Also
// with every polygon offset in 1.5 m tiles (a tile's side every few metres
// of each map).
class ClipperOffsetAgreesWithBoost : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Tiles, ClipperOffsetAgreesWithBoost, ::testing::Values(0.0, 1.5),
                         [](const auto& info) { return info.param > 0.0 ? std::string("Tiled") : std::string("Whole"); });
TEST_P(ClipperOffsetAgreesWithBoost, OnScannedAndDrawnMaps) {
  CSpaceOptions options;  // the explorer's
  options.robot_radius_m = 0.27;
  options.clearance_margin_m = 0.05;
  options.offset_tile_m = GetParam();
  options.offset_tile_min_vertices = 0;
  const double shrink = options.robot_radius_m + options.clearance_margin_m;
  auto reference_options = options;
  reference_options.boost_offset = true;
  int map_index = 0;
  for (const auto& map : oracle_maps()) {
    SCOPED_TRACE("map " + std::to_string(map_index++) + ", " + std::to_string(mapping::vertex_count(map)) + " vertices");
    ASSERT_FALSE(map.empty());
    ConfigurationSpace ours, reference;
    ASSERT_TRUE(ours.build(map, options).ok);
    ASSERT_TRUE(reference.build(map, reference_options).ok);
    ASSERT_FALSE(ours.empty());
    // The round joins' vertices lie on the arc in both; between them the
    // chords differ by at most the sagitta (6 mm at 16 per circle), plus the
    // simplification's epsilon on either side.
    mapping::MultiPolygon a, b, diff;
    for (const auto& p : ours.polygons()) a.push_back(p.geometry);
    for (const auto& p : reference.polygons()) b.push_back(p.geometry);
    boost::geometry::sym_difference(a, b, diff);
    const double perimeter = boost::geometry::perimeter(b);
    EXPECT_LT(boost::geometry::area(diff), 0.01 * perimeter) << "area " << boost::geometry::area(a) << " vs "
                                                            << boost::geometry::area(b);
    // The same pieces of any size (slivers at the clearance may differ).
    auto big_pieces = [](const TypedMultiPolygon& polygons) {
      int n = 0;
      for (const auto& p : polygons) n += boost::geometry::area(p.geometry) > 0.05 ? 1 : 0;
      return n;
    };
    EXPECT_EQ(big_pieces(ours.polygons()), big_pieces(reference.polygons()));
    // Clearance: robot_radius + margin - simplify epsilon, less how far a
    // round join's chords cut into its arc (at most 1 mm in ours; 1-2 mm
    // in Boost's on these maps) and the grid. At vertices and mid-edges.
    const double sagitta = 2e-3;
    for (const auto* cs : {&ours, &reference}) {
      double least = std::numeric_limits<double>::infinity();
      for (const auto& e : cs->edges()) {
        const Point mid(0.5 * (e.a.x() + e.b.x()), 0.5 * (e.a.y() + e.b.y()));
        least = std::min({least, min_distance_to_edges(e.a, map), min_distance_to_edges(mid, map)});
        ASSERT_TRUE(boost::geometry::covered_by(e.a, mapping::geometry_of(map)));
      }
      EXPECT_GE(least, shrink - options.simplify_epsilon_m - sagitta - 2e-5) << (cs == &ours ? "ours" : "Boost");
    }
  }
}

// The drawn map's 0.8 m passage is open for a 0.27 m robot with a 0.05 m
// margin (0.64 m): both halls and the passage are one piece.
TEST(ConfigurationSpace, ClipperOffsetKeepsAPassageTheRobotFitsThroughOpen) {
  CSpaceOptions options;
  options.robot_radius_m = 0.27;
  options.clearance_margin_m = 0.05;
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build(oracle_maps().back(), options).ok);
  EXPECT_EQ(cs.polygons().size(), 1u);
  const int hall = cs.piece_of(Point(1, 1.5));
  EXPECT_GE(hall, 0);
  EXPECT_EQ(cs.piece_of(Point(7, 4.5)), hall);  // in the passage
  EXPECT_EQ(cs.piece_of(Point(11, 7.5)), hall);
  EXPECT_EQ(cs.piece_of(Point(5, 4.5)), -1);   // beside it: wall
  // 0.84 m closes it: two pieces.
  options.clearance_margin_m = 0.15;
  ASSERT_TRUE(cs.build(oracle_maps().back(), options).ok);
  EXPECT_EQ(cs.polygons().size(), 2u);
  EXPECT_NE(cs.piece_of(Point(1, 1.5)), cs.piece_of(Point(11, 7.5)));
}

mapping::MultiPolygon geometry_of(const mapping::TypedOpResult& offset) {
  mapping::MultiPolygon g;
  for (const auto& p : offset.polygons) g.push_back(p.geometry);
  return g;
}

// The explorer's offset (0.27 m radius, 0.05 m margin), untyped, in tiles of
// tile_m (0: whole) for every polygon however few its vertices.
InwardOffset untyped_offset(double tile_m) {
  InwardOffset how;
  how.distance_m = 0.32;
  how.type_edges = false;
  how.tile_m = tile_m;
  how.tile_min_vertices = 0;
  return how;
}

// Tiles change nothing but the rounding where their results meet: on every
// oracle map, offset in 1.5 m tiles (every polygon tiled) and whole, the
// same set within 10 um times the perimeter, in as many pieces.
TEST(InwardOffset, TilesGiveTheWholePolygonsOffset) {
  const InwardOffset whole = untyped_offset(0.0);
  const InwardOffset tiled = untyped_offset(1.5);
  int map_index = 0;
  for (const auto& map : oracle_maps()) {
    SCOPED_TRACE("map " + std::to_string(map_index++));
    const auto a = offset_inward(map, whole);
    const auto b = offset_inward(map, tiled);
    ASSERT_TRUE(a.ok && b.ok) << a.error << b.error;
    ASSERT_FALSE(a.polygons.empty());
    mapping::MultiPolygon diff;
    boost::geometry::sym_difference(geometry_of(a), geometry_of(b), diff);
    EXPECT_LT(boost::geometry::area(diff), 1e-5 * boost::geometry::perimeter(geometry_of(a)));
    EXPECT_EQ(a.polygons.size(), b.polygons.size());
    EXPECT_TRUE(boost::geometry::is_valid(geometry_of(b)));
  }
}

// Simplified tile by tile (InwardOffset::simplify_epsilon_m), a tiled
// offset stays within the epsilon of the exact offset: every vertex of it
// lies within the epsilon of the unsimplified whole offset's boundary (and
// that set's vertices within the epsilon of its boundary), in as many
// pieces, valid, with fewer vertices than the tiles unsimplified.
TEST(InwardOffset, TilesSimplifiedStayWithinTheEpsilon) {
  const InwardOffset whole = untyped_offset(0.0);
  const InwardOffset tiled = untyped_offset(1.5);
  InwardOffset simplified = tiled;
  simplified.simplify_epsilon_m = 0.01;
  int map_index = 0;
  for (const auto& map : oracle_maps()) {
    SCOPED_TRACE("map " + std::to_string(map_index++));
    const auto exact = offset_inward(map, whole);
    const auto raw = offset_inward(map, tiled);
    const auto simple = offset_inward(map, simplified);
    ASSERT_TRUE(exact.ok && raw.ok && simple.ok) << exact.error << raw.error << simple.error;
    ASSERT_FALSE(exact.polygons.empty());
    EXPECT_EQ(simple.polygons.size(), exact.polygons.size());
    EXPECT_TRUE(boost::geometry::is_valid(geometry_of(simple)));
    EXPECT_LT(mapping::vertex_count(simple.polygons), mapping::vertex_count(raw.polygons));
    double worst = 0.0, worst_back = 0.0;
    for (const auto& p : simple.polygons)
      for (const auto& q : p.geometry.outer()) worst = std::max(worst, min_distance_to_edges(q, exact.polygons));
    for (const auto& p : exact.polygons)
      for (const auto& q : p.geometry.outer()) worst_back = std::max(worst_back, min_distance_to_edges(q, simple.polygons));
    // The grid's rounding (10 um) on top.
    EXPECT_LE(worst, simplified.simplify_epsilon_m + 2e-5);
    EXPECT_LE(worst_back, simplified.simplify_epsilon_m + 2e-5);
  }
}

// A tile whose simplified rings cannot be shown apart cheaply keeps them
// as the offset made them: 300 teeth 1 m wide and 200 m long side by side
// in one tile (each of the 600 long edges beside all 6,500 edges: a sweep
// by x tests about 4 million pairs, more than 64 per edge) come out with
// the vertices of the unsimplified offset (without the bound: 3,652 of
// 6,483).
TEST(InwardOffset, ATileOfLongRingsSideBySideKeepsItsRings) {
  std::vector<Point> ring{Point(0, 0), Point(0, -1)};
  for (int t = 0; t < 300; ++t) {
    const double y = 2.0 * t;
    ring.insert(ring.end(), {Point(200, y - 1), Point(200, y), Point(1, y), Point(1, y + 1)});
  }
  ring.insert(ring.end(), {Point(200, 599), Point(200, 600), Point(0, 600)});
  const TypedMultiPolygon map{typed_polygon(RingSpec{ring, {}})};
  ASSERT_TRUE(boost::geometry::is_valid(map[0].geometry));
  InwardOffset how = untyped_offset(1000.0);
  const auto raw = offset_inward(map, how);
  how.simplify_epsilon_m = 0.01;
  const auto simple = offset_inward(map, how);
  ASSERT_TRUE(raw.ok && simple.ok) << raw.error << simple.error;
  ASSERT_EQ(raw.polygons.size(), simple.polygons.size());
  // Only the union's last 0.5 mm touched it: the arcs' vertices are all there.
  EXPECT_GE(mapping::vertex_count(simple.polygons), mapping::vertex_count(raw.polygons) * 9 / 10);
}

// Two halls joined by a corridor 0.7 m wide (open for 0.32 m: a strip 6 cm
// wide): straight along the side of two 1 m tiles, or slanted across the
// sides of many. One piece, tiled as whole; the halls' middles are tiles
// whose input no wall reaches.
TEST(InwardOffset, PiecesJoinAcrossTileSides) {
  const std::vector<TypedMultiPolygon> maps{
      {typed_polygon(RingSpec{{Point(0, 0), Point(20, 0), Point(20, 20), Point(5.35, 20), Point(5.35, 30),
                               Point(20, 30), Point(20, 40), Point(0, 40), Point(0, 30), Point(4.65, 30),
                               Point(4.65, 20), Point(0, 20)},
                              {}})},
      {typed_polygon(RingSpec{{Point(0, 0), Point(20, 0), Point(20, 20), Point(10.7826, 20), Point(15.7826, 30),
                               Point(20, 30), Point(20, 40), Point(0, 40), Point(0, 30), Point(15, 30), Point(10, 20),
                               Point(0, 20)},
                              {}})}};
  for (const auto& map : maps) {
    const auto tiled = offset_inward(map, untyped_offset(1.0));
    ASSERT_TRUE(tiled.ok) << tiled.error;
    const auto whole = offset_inward(map, untyped_offset(0.0));
    ASSERT_TRUE(whole.ok) << whole.error;
    ASSERT_EQ(whole.polygons.size(), 1u);
    EXPECT_EQ(tiled.polygons.size(), 1u);
    EXPECT_NEAR(mapping::area(tiled.polygons), mapping::area(whole.polygons), 1e-4);
    EXPECT_TRUE(boost::geometry::is_valid(geometry_of(tiled)));
  }
}

// Coordinates the integer grid cannot hold are refused, not wrapped.
TEST(InwardOffset, RefusesCoordinatesBeyondItsGrid) {
  InwardOffset how;
  how.distance_m = 0.32;
  EXPECT_TRUE(offset_inward({typed_polygon(rectangle(1e8, 0, 1e8 + 10, 10))}, how).ok);
  const auto far = offset_inward({typed_polygon(rectangle(1e12, 0, 1e12 + 10, 10))}, how);
  EXPECT_FALSE(far.ok);
  EXPECT_NE(far.error.find("beyond"), std::string::npos);
  auto nan = typed_polygon(rectangle(0, 0, 10, 10));
  nan.geometry.outer()[1].x(std::nan(""));
  EXPECT_FALSE(offset_inward({nan}, how).ok);
}

// Long edges across many tiles (a comb of 100 teeth 2 m wide and 1 km
// long): every edge would be listed in some 80 tiles' keys, so the polygon
// is offset whole (one computed result in the cache), not in 7,000 tiles.
TEST(InwardOffset, APolygonOfLongEdgesAcrossManyTilesIsOffsetWhole) {
  std::vector<Point> ring{Point(0, 0), Point(400, 0)};
  for (int t = 99; t >= 0; --t) {
    const double x = 4.0 * t;
    ring.insert(ring.end(), {Point(x + 2, 10), Point(x + 2, 1000), Point(x, 1000), Point(x, 10)});
  }
  ring.pop_back();  // (0, 10) -> (0, 0) closes it
  const TypedMultiPolygon map{typed_polygon(RingSpec{ring, {}})};
  ASSERT_TRUE(boost::geometry::is_valid(map[0].geometry));
  ASSERT_GE(mapping::vertex_count(map), 400u);
  const InwardOffset how = untyped_offset(12.0);
  OffsetTileCache cache;
  const auto offset = offset_inward(map, how, &cache);
  ASSERT_TRUE(offset.ok) << offset.error;
  EXPECT_EQ(cache.counters().misses, 1);
  EXPECT_EQ(cache.entries(), 1u);
  EXPECT_GT(mapping::area(offset.polygons), 100 * 1.36 * 990.0 * 0.99);
}

// A polygon whose box averages more than tile_min_vertices vertices per
// tile (a ragged, scanned wall all round: 10 per m^2) is offset in tiles of
// half the side, point for point as if asked for them; a sparse one keeps
// the side asked for.
TEST(InwardOffset, ADenseRaggedPolygonIsOffsetInSmallerTiles) {
  auto square_with_teeth = [](double side_m, double tooth_m) {
    const int n = static_cast<int>(std::lround(side_m / tooth_m));
    std::vector<Point> ring;
    for (int i = 0; i < n; ++i) ring.insert(ring.end(), {Point(i * tooth_m, 0), Point((i + 0.5) * tooth_m, 0.01)});
    for (int i = 0; i < n; ++i)
      ring.insert(ring.end(), {Point(side_m, i * tooth_m), Point(side_m - 0.01, (i + 0.5) * tooth_m)});
    for (int i = 0; i < n; ++i)
      ring.insert(ring.end(), {Point(side_m - i * tooth_m, side_m), Point(side_m - (i + 0.5) * tooth_m, side_m - 0.01)});
    for (int i = 0; i < n; ++i)
      ring.insert(ring.end(), {Point(0, side_m - i * tooth_m), Point(0.01, side_m - (i + 0.5) * tooth_m)});
    return TypedMultiPolygon{typed_polygon(RingSpec{ring, {}})};
  };
  auto offset_in = [](const TypedMultiPolygon& map, double tile_m, OffsetTileCache& cache) {
    InwardOffset how = untyped_offset(tile_m);
    how.tile_min_vertices = 400;
    auto result = offset_inward(map, how, &cache);
    EXPECT_TRUE(result.ok) << result.error;
    return result;
  };
  const auto dense = square_with_teeth(20.0, 0.04);  // 4,000 vertices on 400 m^2
  ASSERT_TRUE(boost::geometry::is_valid(dense[0].geometry));
  OffsetTileCache asked_12, asked_6;
  const auto in_12 = offset_in(dense, 12.0, asked_12);
  const auto in_6 = offset_in(dense, 6.0, asked_6);
  EXPECT_EQ(asked_12.counters().misses, asked_6.counters().misses);
  EXPECT_TRUE(boost::geometry::equals(geometry_of(in_12), geometry_of(in_6)));
  EXPECT_EQ(mapping::vertex_count(in_12.polygons), mapping::vertex_count(in_6.polygons));

  const auto sparse = square_with_teeth(100.0, 0.4);  // 2,000 vertices on 10,000 m^2
  OffsetTileCache sparse_12, sparse_6;
  offset_in(sparse, 12.0, sparse_12);
  offset_in(sparse, 6.0, sparse_6);
  EXPECT_LT(sparse_12.counters().misses, sparse_6.counters().misses);
}

// Maps that grow scan by scan (a 40 m long building, a 10 m laser): with a
// cache the offset is the one computed afresh, point for point, and most
// tiles come from the cache, as the map changes only within the laser's
// reach of the robot.
class InwardOffsetCache : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Simplified, InwardOffsetCache, ::testing::Values(0.0, 0.01), [](const auto& info) {
  return info.param > 0.0 ? std::string("ByTheEpsilon") : std::string("Not");
});
TEST_P(InwardOffsetCache, KeepsTilesAndChangesNothing) {
  InwardOffset how = untyped_offset(2.0);
  how.simplify_epsilon_m = GetParam();
  OffsetTileCache cache;
  std::mt19937_64 rng(5);
  const auto walls = mapping::testing::random_room(40, 10, 8, rng);
  for (int scans = 20; scans <= 40; scans += 2) {
    SCOPED_TRACE(std::to_string(scans) + " scans");
    const auto map = scanned_map(walls, 40, 10, scans, 11);
    const auto fresh = offset_inward(map, how);
    const auto kept = offset_inward(map, how, &cache);
    ASSERT_TRUE(fresh.ok && kept.ok);
    ASSERT_EQ(fresh.polygons.size(), kept.polygons.size());
    for (std::size_t i = 0; i < fresh.polygons.size(); ++i) {
      const auto& f = fresh.polygons[i].geometry;
      const auto& k = kept.polygons[i].geometry;
      ASSERT_EQ(f.inners().size(), k.inners().size());
      auto same = [](const mapping::Ring& x, const mapping::Ring& y) {
        if (x.size() != y.size()) return false;
        for (std::size_t j = 0; j < x.size(); ++j)
          if (x[j].x() != y[j].x() || x[j].y() != y[j].y()) return false;
        return true;
      };
      EXPECT_TRUE(same(f.outer(), k.outer()));
      for (std::size_t h = 0; h < f.inners().size(); ++h) EXPECT_TRUE(same(f.inners()[h], k.inners()[h]));
    }
  }
  EXPECT_GT(cache.counters().hits, cache.counters().misses);
  // Entries not used by the last kKeptCalls calls are dropped: after that
  // many calls on one map, only that map's tiles are kept.
  const auto last = scanned_map(walls, 40, 10, 20, 11);
  for (int k = 0; k < OffsetTileCache::kKeptCalls; ++k) ASSERT_TRUE(offset_inward(last, how, &cache).ok);
  OffsetTileCache alone;
  ASSERT_TRUE(offset_inward(last, how, &alone).ok);
  EXPECT_EQ(cache.entries(), alone.entries());
  EXPECT_GT(alone.entries(), 4u);
}

// Uniform random points over a map's box grown by 1 m.
class PointSampler {
 public:
  explicit PointSampler(const TypedMultiPolygon& map) {
    const auto box = boost::geometry::return_envelope<mapping::Box>(mapping::geometry_of(map));
    x_ = std::uniform_real_distribution<double>(box.min_corner().x() - 1, box.max_corner().x() + 1);
    y_ = std::uniform_real_distribution<double>(box.min_corner().y() - 1, box.max_corner().y() + 1);
  }
  Point operator()(std::mt19937_64& rng) { return Point(x_(rng), y_(rng)); }
  double y(std::mt19937_64& rng) { return y_(rng); }

 private:
  std::uniform_real_distribution<double> x_, y_;
};

// covers() and piece_of() (a ray's crossings through the edge index) against
// bg::covered_by on every polygon, at random points of scanned maps.
TEST(ConfigurationSpace, PieceOfAgreesWithCoveredBy) {
  CSpaceOptions options;
  options.robot_radius_m = 0.27;
  std::mt19937_64 rng(3);
  int inside = 0, outside = 0;
  for (const auto& map : oracle_maps()) {
    ConfigurationSpace cs;
    ASSERT_TRUE(cs.build(map, options).ok);
    PointSampler sample(map);
    for (int k = 0; k < 2000; ++k) {
      const Point p = sample(rng);
      int expected = -1;
      for (std::size_t i = 0; i < cs.polygons().size(); ++i)
        if (boost::geometry::covered_by(p, cs.polygons()[i].geometry)) expected = static_cast<int>(i);
      ASSERT_EQ(cs.piece_of(p), expected) << p.x() << "," << p.y();
      ASSERT_EQ(cs.covers(p), expected >= 0);
      (expected >= 0 ? inside : outside)++;
    }
    // Vertices lie on the boundary: covered.
    for (const auto& e : cs.edges()) ASSERT_EQ(cs.piece_of(e.a), static_cast<int>(e.polygon));
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 1000);
}

// Without edge types (the planner's C-space) the same free space as with
// them: the same pieces, the area within the simplification's epsilon times
// the perimeter (the typed simplification keeps the vertices where types
// change), every edge kObstacle.
TEST(ConfigurationSpace, UntypedIsTheTypedSpaceWithoutTypes) {
  CSpaceOptions untyped;
  untyped.robot_radius_m = 0.27;
  CSpaceOptions typed = untyped;
  typed.edge_types = true;
  int frontier_edges = 0;
  for (const auto& map : oracle_maps()) {
    ConfigurationSpace a, b;
    ASSERT_TRUE(a.build(map, untyped).ok);
    ASSERT_TRUE(b.build(map, typed).ok);
    ASSERT_EQ(a.polygons().size(), b.polygons().size());
    mapping::MultiPolygon ga, gb, diff;
    for (const auto& p : a.polygons()) ga.push_back(p.geometry);
    for (const auto& p : b.polygons()) gb.push_back(p.geometry);
    boost::geometry::sym_difference(ga, gb, diff);
    EXPECT_LT(boost::geometry::area(diff), untyped.simplify_epsilon_m * boost::geometry::perimeter(gb));
    for (const auto& e : a.edges()) ASSERT_EQ(e.type, EdgeType::kObstacle);
    for (const auto& e : b.edges()) frontier_edges += e.type == EdgeType::kFrontier ? 1 : 0;
  }
  EXPECT_GT(frontier_edges, 0);  // the typed ones do have frontier edges: the maps are scans
}

// boundary_within() (edges near the point only) against distance_to_boundary()
// at random points of scanned maps, at radii from a millimetre to a metre, and
// near the boundary, where the answer changes.
TEST(ConfigurationSpace, BoundaryWithinAgreesWithTheDistance) {
  CSpaceOptions options;
  options.robot_radius_m = 0.27;
  std::mt19937_64 rng(11);
  int near = 0, far = 0;
  for (const auto& map : oracle_maps()) {
    ConfigurationSpace cs;
    ASSERT_TRUE(cs.build(map, options).ok);
    PointSampler sample(map);
    for (int k = 0; k < 2000; ++k) {
      Point p = sample(rng);
      if (k % 2 == 1) {  // a point within a few millimetres of a vertex
        const auto& e = cs.edges()[rng() % cs.edges().size()];
        p = Point(e.a.x() + 1e-3 * static_cast<double>(rng() % 7) - 3e-3, e.a.y() + 1e-3 * static_cast<double>(rng() % 7) - 3e-3);
      }
      const double radius = k % 3 == 0 ? 1e-3 : (k % 3 == 1 ? 0.05 : 1.0);
      const bool expected = cs.distance_to_boundary(p) < radius;
      ASSERT_EQ(cs.boundary_within(p, radius), expected) << p.x() << "," << p.y() << " r " << radius;
      (expected ? near : far)++;
    }
  }
  EXPECT_GT(near, 500);
  EXPECT_GT(far, 500);
}

// edges_near() holds every edge within the radius (a test of every edge),
// each once, on scanned maps: the approach points search only those.
TEST(ConfigurationSpace, EdgesNearHoldEveryEdgeWithinTheRadius) {
  CSpaceOptions options;
  options.robot_radius_m = 0.27;
  std::mt19937_64 rng(12);
  std::size_t listed = 0, within = 0;
  for (const auto& map : oracle_maps()) {
    ConfigurationSpace cs;
    ASSERT_TRUE(cs.build(map, options).ok);
    PointSampler sample(map);
    for (int k = 0; k < 500; ++k) {
      const Point p = sample(rng);
      const double radius = k % 2 == 0 ? 0.3 : 3.0;
      auto near = cs.edges_near(p, radius);
      std::sort(near.begin(), near.end());
      ASSERT_EQ(std::adjacent_find(near.begin(), near.end()), near.end()) << "an edge listed twice";
      listed += near.size();
      for (std::uint32_t i = 0; i < cs.edges().size(); ++i) {
        const auto& e = cs.edges()[i];
        if (distance(p, closest_point_on_segment(p, e.a, e.b)) > radius) continue;
        ++within;
        ASSERT_TRUE(std::binary_search(near.begin(), near.end(), i))
            << "edge " << i << " within " << radius << " m of " << p.x() << "," << p.y() << " is not listed";
      }
    }
  }
  EXPECT_GT(within, 1000u);
  EXPECT_GE(listed, within);
  EXPECT_TRUE(ConfigurationSpace().edges_near(Point(0, 0), 1.0).empty());
}

// segment_free() (a grid walk) against a test of every boundary edge, on
// random segments of scanned maps: long and short, axis-parallel, and ending
// on C-space vertices (touching counts as not free).
TEST(ConfigurationSpace, SegmentFreeAgreesWithEveryEdge) {
  CSpaceOptions options;
  options.robot_radius_m = 0.27;
  std::mt19937_64 rng(5);
  int free = 0, blocked = 0;
  for (const auto& map : oracle_maps()) {
    ConfigurationSpace cs;
    ASSERT_TRUE(cs.build(map, options).ok);
    ASSERT_FALSE(cs.edges().empty());
    PointSampler sample(map);
    std::uniform_real_distribution<double> near(-0.5, 0.5);
    std::uniform_int_distribution<std::size_t> pick(0, cs.edges().size() - 1);
    for (int k = 0; k < 3000; ++k) {
      Point a = sample(rng), b;
      switch (k % 4) {
        case 0: b = sample(rng); break;
        case 1: b = Point(a.x() + near(rng), a.y() + near(rng)); break;
        case 2: b = Point(a.x(), sample.y(rng)); break;  // vertical
        default:
          a = cs.edges()[pick(rng)].a;  // on a vertex
          b = Point(a.x() + 4 * near(rng), a.y() + 4 * near(rng));
      }
      bool expected = true;
      for (const auto& e : cs.edges()) expected = expected && !segments_intersect(a, b, e.a, e.b);
      ASSERT_EQ(cs.segment_free(a, b), expected) << a.x() << "," << a.y() << " - " << b.x() << "," << b.y();
      (expected ? free : blocked)++;
    }
  }
  EXPECT_GT(free, 2000);
  EXPECT_GT(blocked, 2000);
}

// The reflex nodes against the definition: every reflex vertex (a right turn)
// moved interior_offset_m along the bisector of its edges' left normals (the
// step longer at sharp corners, capped), kept when that point is inside
// (bg::covered_by) and at least half the offset from the boundary. The
// builder decides "inside" from the few millimetres the step crosses, not
// from the whole map: this checks it decides the same.
TEST(ConfigurationSpace, ReflexNodesAreTheVerticesMovedInsideAlongTheirBisectors) {
  CSpaceOptions options;
  options.robot_radius_m = 0.27;
  const double delta = options.interior_offset_m;
  // And a drawn map where the step from a corner lands in something else:
  // a pillar, and a diamond 0.2 mm beyond its corner (6, 6) across the
  // bisector, taken as it is (no offset, no simplification).
  const double k = std::numbers::sqrt2 / 2.0;
  auto beyond = [&](double t, double s) { return Point(6.0 + t * k - s * k, 6.0 + t * k + s * k); };
  const TypedMultiPolygon touching{typed_polygon(
      rectangle(0, 0, 10, 10),
      {rectangle_hole(4, 4, 6, 6), RingSpec{{beyond(2e-4, 0.5), beyond(1.0002, 0.5), beyond(1.0002, -0.5), beyond(2e-4, -0.5)}, {}}})};
  CSpaceOptions as_drawn = options;
  as_drawn.robot_radius_m = as_drawn.clearance_margin_m = as_drawn.simplify_epsilon_m = 0.0;
  std::vector<std::pair<TypedMultiPolygon, CSpaceOptions>> cases;
  for (const auto& map : oracle_maps()) cases.emplace_back(map, options);
  cases.emplace_back(touching, as_drawn);
  int checked = 0, refused = 0;
  for (const auto& [map, map_options] : cases) {
    ConfigurationSpace cs;
    ASSERT_TRUE(cs.build(map, map_options).ok);
    std::map<std::uint32_t, Point> nodes;
    for (std::size_t k = 0; k < cs.reflex_nodes().size(); ++k) nodes.emplace(cs.reflex_edges()[k], cs.reflex_nodes()[k]);
    for (std::uint32_t i = 0; i < cs.edges().size(); ++i) {
      const auto& in = cs.edges()[i];
      const auto& out = cs.edges()[in.next];
      const double ux = in.b.x() - in.a.x(), uy = in.b.y() - in.a.y(), vx = out.b.x() - out.a.x(),
                   vy = out.b.y() - out.a.y();
      const double lu = std::hypot(ux, uy), lv = std::hypot(vx, vy);
      if (!((ux * vy - uy * vx) / (lu * lv) < -1e-9)) {
        EXPECT_EQ(nodes.count(i), 0u) << "a node at a vertex that is not reflex";
        continue;
      }
      const double sx = -uy / lu - vy / lv, sy = ux / lu + vx / lv, len = std::hypot(sx, sy);
      if (len < 1e-9) continue;  // a spike: the edges run back on themselves
      const double step = delta / std::max(len / 2.0, 0.1);
      const Point expected(in.b.x() + step * sx / len, in.b.y() + step * sy / len);
      bool inside = false;
      for (const auto& polygon : cs.polygons()) inside = inside || boost::geometry::covered_by(expected, polygon.geometry);
      const bool kept = inside && cs.distance_to_boundary(expected) >= 0.5 * delta;
      ASSERT_EQ(nodes.count(i), kept ? 1u : 0u) << expected.x() << "," << expected.y();
      refused += inside ? 0 : 1;
      if (kept) {
        EXPECT_DOUBLE_EQ(nodes[i].x(), expected.x());
        EXPECT_DOUBLE_EQ(nodes[i].y(), expected.y());
        EXPECT_EQ(cs.piece_of(nodes[i]), static_cast<int>(in.polygon));
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 200);
  EXPECT_GE(refused, 1);  // the pillar's corner at least
}

}  // namespace
}  // namespace pex::planning
