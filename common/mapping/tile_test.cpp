#include "mapping/tile.hpp"

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
  EXPECT_NEAR(area(TypedMultiPolygon{layer[0]}), area(TypedMultiPolygon{room}), 1e-12);  // kept as it was
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

}  // namespace
}  // namespace pex::mapping
