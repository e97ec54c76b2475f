#pragma once
// The post-operation edge-type reassignment pass (paper, "Modifications of
// clipping"): after a union, difference or offset computed on plain geometry,
// every output edge takes the type of the input edge that matches it best by
// the penalty P = p1 + p2 + |d1| + |d2|.
//
// Candidates come from a Boost.Geometry rtree over the input segments instead
// of the paper's bound-ordered scan of Vatti's internal structures; the search
// stops at a zero-penalty obstacle edge.
#include <cstdint>
#include <memory>
#include <vector>

#include <boost/geometry/index/rtree.hpp>

#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

// Penalty of explaining output edge (out_a, out_b) by input edge (in_a, in_b).
// p1, p2: perpendicular distances of the input edge's end points from the
// line through the output edge. d1, d2: how far the output edge's ends lie
// beyond the input edge's projection onto it, measured along the output edge
// (the paper measures them along y because Vatti's sweep orders edges by y;
// the edge's own direction is the same idea without a preferred axis). A gap
// between the projections counts in full, so P is never less than the
// distance between the two edges, which is what makes the indexed search
// exact. A zero-length output edge scores twice its distance from the input.
double edge_match_penalty(const Point& out_a, const Point& out_b, const Point& in_a,
                          const Point& in_b);

// Penalties closer than this count as equal; at equal penalty the more
// specific type wins (obstacle before frontier before border).
inline constexpr double kPenaltyTieTolerance = 1e-9;

// True if candidate (penalty, type) beats the current best under the tie rule.
inline bool better_match(double penalty, EdgeType type, double best_penalty, EdgeType best_type) {
  if (penalty < best_penalty - kPenaltyTieTolerance) return true;
  if (penalty <= best_penalty + kPenaltyTieTolerance) return type < best_type;
  return false;
}

// The input edges of an operation, indexed for the reassignment pass.
class EdgeTypeIndex {
 public:
  struct Edge {
    Point a, b;
    EdgeType type;
  };

  // Adds every edge of the polygons with its own type.
  void add(const TypedMultiPolygon& polygons);
  void add(const TypedPolygon& polygon);
  // Adds every edge of the polygons with one type (origin decides the type).
  void add_as(const TypedMultiPolygon& polygons, EdgeType type);
  void add_as(const MultiPolygon& polygons, EdgeType type);
  // Adds one edge.
  void add_edge(const Point& a, const Point& b, EdgeType type);
  // Builds the rtree (bulk loading); call after the last add. Without it
  // match() scans every edge.
  void build();

  const std::vector<Edge>& edges() const { return edges_; }

  struct Match {
    EdgeType type = EdgeType::kFrontier;
    double penalty = 0.0;
    std::int64_t edge = -1;  // index into edges(), -1 if the index is empty
    int candidates = 0;      // penalties computed
  };
  // The best input edge for output edge (a, b): the same answer as scoring
  // every input edge. Candidates are the edges whose boxes come within
  // `search_radius_m` of the output edge's box (the expected distance between
  // an output edge and its source); the radius grows when the best penalty
  // found is larger.
  Match match(const Point& a, const Point& b, double search_radius_m) const;

 private:
  using Value = std::pair<Box, std::uint32_t>;
  using Tree = boost::geometry::index::rtree<Value, boost::geometry::index::rstar<16>>;
  std::vector<Edge> edges_;
  std::unique_ptr<Tree> tree_;
};

struct ReassignStats {
  std::int64_t edges = 0;
  std::int64_t candidates = 0;  // penalties computed over all edges
};

}  // namespace pex::mapping
