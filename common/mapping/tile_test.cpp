#include "mapping/tile.hpp"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

namespace pex::mapping {
namespace {

using E = EdgeType;

TypedPolygon square(double x0, double y0, double x1, double y1, EdgeType type) {
  TypedPolygon p;
  p.geometry.outer() = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}, {x0, y0}};
  p.edge_types = {{type, type, type, type}};
  return p;
}

// The planning layer is derived on first use: free minus obstacles, with the
// free map's edges as frontiers and the band's as obstacles.
TEST(Tile, PlanningLayerIsFreeMinusObstaclesComputedOnFirstUse) {
  const Box box(Point(0, 0), Point(8, 8));
  const Tile tile(box, {square(1, 1, 7, 7, E::kObstacle)}, {square(3, 3, 4, 4, E::kObstacle)}, nullptr,
                  {0.01, true});
  EXPECT_FALSE(tile.planning_computed());
  const TypedMultiPolygon& planning = tile.planning();
  EXPECT_TRUE(tile.planning_computed());
  EXPECT_FALSE(tile.planning_failed());
  ASSERT_EQ(planning.size(), 1u);
  EXPECT_NEAR(area(planning), 36.0 - 1.0, 1e-9);
  ASSERT_EQ(planning[0].edge_types.size(), 2u);  // the room and the pillar's hole
  for (EdgeType t : planning[0].edge_types[0]) EXPECT_EQ(t, E::kFrontier);
  for (EdgeType t : planning[0].edge_types[1]) EXPECT_EQ(t, E::kObstacle);
  EXPECT_EQ(&tile.planning(), &planning);  // kept, not recomputed
}

// A difference that fails its checks leaves the newest planning layer computed
// for an earlier version of the tile in place, and says so. Versions never
// read in between are skipped, not kept alive.
TEST(Tile, FailedPlanningFallsBackToTheLastGoodLayer) {
  const Box box(Point(0, 0), Point(8, 8));
  const Tile good(box, {square(1, 1, 7, 7, E::kObstacle)}, {square(3, 3, 4, 4, E::kObstacle)}, nullptr,
                  {0.01, true});
  ASSERT_FALSE(good.planning_failed());
  const Tile unread(box, {square(1, 1, 7.5, 7, E::kObstacle)}, {square(3, 3, 4, 4, E::kObstacle)},
                    good.last_good_planning(), {0.01, true});
  // An obstacle ring the wrong way round (clockwise: negative area) puts the
  // difference outside its area bounds.
  TypedPolygon clockwise = square(2, 2, 5, 5, E::kObstacle);
  bg::reverse(clockwise.geometry);
  const Tile bad(box, {square(1, 1, 7.5, 7.5, E::kObstacle)}, {clockwise}, unread.last_good_planning(),
                 {0.01, true});
  EXPECT_TRUE(bad.planning_failed()) << "area " << area(bad.planning());
  EXPECT_FALSE(bad.planning_error().empty());
  EXPECT_EQ(&bad.planning(), &good.planning());  // the last good layer itself
  EXPECT_FALSE(unread.planning_computed());
}

// RDP moves a boundary by up to its tolerance, so a polygon that an update
// changed can cross a neighbour it left unchanged: here the top edge of a
// room has a 5 mm dent (below the 1 cm tolerance) and a pillar's corner sits
// in the dent. The neighbour is checked with the simplified room, so the
// room keeps its dent; checked alone (what the insert and merge did before
// issue 16's fix) the simplified room crosses the pillar.
TEST(SimplifyAndCheck, ASimplifiedPolygonIsCheckedWithTheNeighboursItComesNear) {
  TypedPolygon room;
  room.geometry.outer() = {{0, 0}, {4, 0}, {4, 1}, {3, 1}, {2, 0.995}, {1, 1}, {0, 1}, {0, 0}};
  room.edge_types = {{E::kObstacle, E::kObstacle, E::kFrontier, E::kFrontier, E::kFrontier, E::kFrontier,
                      E::kObstacle}};
  TypedPolygon pillar;
  pillar.geometry.outer() = {{2, 0.998}, {2.1, 1.05}, {1.9, 1.05}, {2, 0.998}};
  pillar.edge_types = {{E::kObstacle, E::kObstacle, E::kObstacle}};
  const TypedMultiPolygon both{room, pillar};
  ASSERT_TRUE(is_valid(both));

  TypedMultiPolygon alone{room};
  std::string why;
  ASSERT_TRUE(simplify_and_check(alone, 1, 0.01, why)) << why;
  EXPECT_LT(vertex_count(alone), vertex_count(TypedMultiPolygon{room}));  // the dent went
  EXPECT_FALSE(is_valid(TypedMultiPolygon{alone[0], pillar}));

  TypedMultiPolygon layer{room, pillar};
  ASSERT_TRUE(simplify_and_check(layer, 1, 0.01, why)) << why;
  std::string reason;
  EXPECT_TRUE(is_valid(layer, &reason)) << reason;
  // The dent's vertex stays (the room is simplified again with a finer
  // tolerance, which keeps it; before, the room was kept as it came).
  const auto& top = layer[0].geometry.outer();
  EXPECT_TRUE(std::any_of(top.begin(), top.end(), [](const Point& p) { return bg::equals(p, Point(2, 0.995)); }));
}

// A kept polygon far from the changed ones is not looked at: the check costs
// what the changed polygons cost, not the whole tile.
TEST(SimplifyAndCheck, FarNeighboursDoNotStopTheSimplification) {
  TypedPolygon room;
  room.geometry.outer() = {{0, 0}, {4, 0}, {4, 1}, {3, 1}, {2, 0.995}, {1, 1}, {0, 1}, {0, 0}};
  room.edge_types = {std::vector<EdgeType>(7, E::kFrontier)};
  const TypedPolygon far = square(10, 10, 11, 11, E::kObstacle);
  TypedMultiPolygon layer{room, far};
  std::string why;
  ASSERT_TRUE(simplify_and_check(layer, 1, 0.01, why)) << why;
  EXPECT_LT(vertex_count(layer[0].geometry), 7u);
}

// RDP can fold a polygon by itself: here the room's obstacle floor dips
// 8 mm (below the 1 cm tolerance) under a slit that comes down from the top
// to 4 mm above it; the straightened floor would cut the slit's end off.
// The room is simplified again with a quarter of the tolerance, which keeps
// the dip and still takes out the top edge's 1 mm bumps. Before, the room
// was stored as it came, every bump kept (and every later check of its
// tile sent to bg::is_valid by what the cheap check cannot clear).
TEST(SimplifyAndCheck, APolygonRdpWouldFoldIsSimplifiedWithAFinerTolerance) {
  TypedPolygon room;
  auto& ring = room.geometry.outer();
  ring = {{0, 0}, {5, -0.008}, {10, 0}, {10, 2}};
  for (int i = 1; i < 10; ++i) ring.push_back({10.0 - 0.5 * i, i % 2 == 0 ? 2.0 : 2.001});  // bumps of 1 mm
  ring.insert(ring.end(), {{5.01, 2}, {5.01, -0.004}, {4.99, -0.004}, {4.99, 2}, {0, 2}, {0, 0}});
  room.edge_types = {std::vector<EdgeType>(ring.size() - 1, E::kFrontier)};
  room.edge_types[0][0] = room.edge_types[0][1] = E::kObstacle;  // the floor: its own run, ends kept
  ASSERT_TRUE(is_valid(TypedMultiPolygon{room}));
  // At the full tolerance the floor's dip goes and the floor crosses the slit.
  EXPECT_FALSE(is_valid(simplify_typed(TypedMultiPolygon{room}, 0.01, false)));

  TypedMultiPolygon layer{room};
  std::string why;
  ASSERT_TRUE(simplify_and_check(layer, 1, 0.01, why)) << why;
  EXPECT_TRUE(is_clearly_valid(layer));
  EXPECT_LT(vertex_count(layer), vertex_count(TypedMultiPolygon{room}) - 5);  // the bumps went
  EXPECT_NEAR(area(layer), area(TypedMultiPolygon{room}), 0.01 * 10.0);
}

}  // namespace
}  // namespace pex::mapping
