#include "mapping/typed_polygon.hpp"

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
  const auto s = simplify_typed({p}, 0.01);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(vertex_count(s), 4u);
  EXPECT_TRUE(is_valid(s));
  EXPECT_NEAR(edge_length(s, E::kFrontier), 4.0, 1e-9);
}

TEST(TypedPolygon, SimplifyNeverMergesAcrossATypeChange) {
  // Collinear bottom side whose middle vertex separates obstacle from frontier.
  const auto p = make({{0, 0}, {2, 0}, {4, 0}, {4, 4}, {0, 4}},
                      {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle});
  const auto s = simplify_typed({p}, 0.5);
  EXPECT_EQ(vertex_count(s), 5u);
  EXPECT_NEAR(edge_length(s, E::kFrontier), 2.0, 1e-12);
  EXPECT_NEAR(edge_length(s, E::kObstacle), 14.0, 1e-12);
}

TEST(TypedPolygon, SimplifyKeepsTheInputWhenTheResultWouldBeInvalid) {
  // A thin spike: RDP with a large tolerance would collapse the ring.
  const auto p = make({{0, 0}, {10, 0}, {10, 0.01}, {0, 0.02}},
                      {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle});
  const auto s = simplify_typed({p}, 1.0);
  EXPECT_TRUE(is_valid(s));
  EXPECT_GT(area(s), 0.0);
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

}  // namespace
}  // namespace pex::mapping
