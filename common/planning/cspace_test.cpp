#include "planning/cspace.hpp"

#include <gtest/gtest.h>

#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

using testing::rectangle;
using testing::rectangle_hole;
using testing::typed_polygon;
using testing::disk;


TEST(ConfigurationSpace, SquareRoomShrinksByTheRadius) {
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10))}, disk(0.5)).ok);
  ASSERT_EQ(cs.polygons().size(), 1u);
  // Boost's buffer is exact to about 1e-6 m.
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
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 4, {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle}))},
                       disk(0.5))
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

}  // namespace
}  // namespace pex::planning
