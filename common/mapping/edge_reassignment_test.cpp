#include "mapping/edge_reassignment.hpp"

#include <random>

#include <gtest/gtest.h>

namespace pex::mapping {
namespace {

// The oracle: every input edge is scored, the best under the same tie rule.
EdgeTypeIndex::Match brute_force_match(const std::vector<EdgeTypeIndex::Edge>& edges, const Point& a,
                                       const Point& b) {
  EdgeTypeIndex::Match best;
  best.penalty = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const double p = edge_match_penalty(a, b, edges[i].a, edges[i].b);
    if (best.edge < 0 || better_match(p, edges[i].type, best.penalty, best.type)) {
      best.penalty = p;
      best.type = edges[i].type;
      best.edge = static_cast<std::int64_t>(i);
    }
  }
  return best;
}

TEST(EdgeMatchPenalty, ZeroForTheSameEdgeAndForAPieceOfIt) {
  EXPECT_NEAR(edge_match_penalty({0, 0}, {4, 0}, {0, 0}, {4, 0}), 0.0, 1e-12);
  EXPECT_NEAR(edge_match_penalty({1, 0}, {3, 0}, {0, 0}, {4, 0}), 0.0, 1e-12);
  EXPECT_NEAR(edge_match_penalty({3, 0}, {1, 0}, {0, 0}, {4, 0}), 0.0, 1e-12);
}

TEST(EdgeMatchPenalty, CountsPerpendicularOffsetsAndOverhang) {
  // Parallel at distance 0.5: p1 = p2 = 0.5.
  EXPECT_NEAR(edge_match_penalty({0, 0}, {4, 0}, {0, 0.5}, {4, 0.5}), 1.0, 1e-12);
  // The output edge sticks out 1 beyond each end of the input edge.
  EXPECT_NEAR(edge_match_penalty({0, 0}, {4, 0}, {1, 0}, {3, 0}), 2.0, 1e-12);
  // Disjoint collinear: the gap counts, so P is at least the distance (4).
  EXPECT_NEAR(edge_match_penalty({0, 0}, {1, 0}, {5, 0}, {6, 0}), 5.0, 1e-12);
}

TEST(EdgeTypeIndex, AtEqualPenaltyObstacleWins) {
  EdgeTypeIndex index;
  index.add_edge({0, 0}, {4, 0}, EdgeType::kFrontier);
  index.add_edge({0, 0}, {4, 0}, EdgeType::kObstacle);
  index.add_edge({0, 0}, {4, 0}, EdgeType::kBorder);
  index.build();
  EXPECT_EQ(index.match({1, 0}, {2, 0}, 1e-6).type, EdgeType::kObstacle);
}

TEST(EdgeTypeIndex, FallsBackToNearestWhenNothingIsWithinTheRadius) {
  EdgeTypeIndex index;
  index.add_edge({0, 0}, {1, 0}, EdgeType::kObstacle);
  index.add_edge({100, 0}, {101, 0}, EdgeType::kFrontier);
  index.build();
  const auto m = index.match({0, 5}, {1, 5}, 1e-6);
  EXPECT_EQ(m.edge, 0);
  EXPECT_EQ(m.type, EdgeType::kObstacle);
}

// The rtree matcher agrees with the brute-force oracle on random edges: on
// pieces of input edges (what clipping produces) and on edges near them.
TEST(EdgeTypeIndex, AgreesWithBruteForceOracle) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> coord(0.0, 20.0), offset(-0.5, 0.5), frac(0.0, 1.0);
  std::bernoulli_distribution coin(0.5);
  for (int round = 0; round < 20; ++round) {
    EdgeTypeIndex index;
    for (int k = 0; k < 300; ++k) {
      const Point a(coord(rng), coord(rng));
      const Point b(a.x() + offset(rng) * 4, a.y() + offset(rng) * 4);
      index.add_edge(a, b, coin(rng) ? EdgeType::kObstacle : EdgeType::kFrontier);
    }
    index.build();
    const auto& edges = index.edges();
    for (int q = 0; q < 300; ++q) {
      const auto& e = edges[static_cast<std::size_t>(q) % edges.size()];
      const double t0 = frac(rng), t1 = frac(rng);
      Point a(e.a.x() + t0 * (e.b.x() - e.a.x()), e.a.y() + t0 * (e.b.y() - e.a.y()));
      Point b(e.a.x() + t1 * (e.b.x() - e.a.x()), e.a.y() + t1 * (e.b.y() - e.a.y()));
      const bool perturbed = q % 2 == 1;
      if (perturbed) {
        a = Point(a.x() + offset(rng) * 0.01, a.y() + offset(rng) * 0.01);
        b = Point(b.x() + offset(rng) * 0.01, b.y() + offset(rng) * 0.01);
      }
      const auto fast = index.match(a, b, perturbed ? 0.01 : 1e-6);
      const auto oracle = brute_force_match(edges, a, b);
      EXPECT_NEAR(fast.penalty, oracle.penalty, 2 * kPenaltyTieTolerance) << "query " << q;
      EXPECT_EQ(fast.type, oracle.type) << "query " << q;
      EXPECT_LT(fast.candidates, static_cast<int>(edges.size()));
    }
  }
}

}  // namespace
}  // namespace pex::mapping
