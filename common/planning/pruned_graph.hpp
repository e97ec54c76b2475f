#pragma once
// The sparse graph the path matrix searches (path_matrix.hpp): nodes are the
// C-space's reflex nodes (0..r-1) and points (start, targets: r..), edges
// the visible pairs a shortest path can use (a reflex pair tangent to the
// boundary at both ends, a point to a reflex node tangent there; never two
// points). And VisibilityCache, which keeps the graph's segment tests from
// one C-space to the next, where the map changed only in places.
#include <array>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "planning/cspace.hpp"

namespace pex::planning {

// The boundary at the reflex nodes, as arrays (the pair loop of the graph
// runs over all of them for each node): per node n its vertex v, the
// neighbours p (before) and q (after), the edge vectors v - p ("in") and
// q - v ("out"), and slack_p2 / slack_q2, the squares of how deep a line
// through the node may pass beyond p or q and still be on a shortest path of
// the node graph (see drops()). The node is v moved interior_offset_m inward
// with both edges kept parallel, so the edge vectors are also the directions
// of the boundary moved to the node.
struct Corners {
  std::vector<double> x, y;  // the node
  std::vector<double> in_x, in_y, out_x, out_y;
  std::vector<double> slack_p2, slack_q2;
  // p - n, v - n, q - n; and orient(p, v, n), orient(v, q, n), both > 0
  // (the node is on the free side, the left, of both edges).
  std::vector<double> pn_x, pn_y, vn_x, vn_y, qn_x, qn_y, in_side, out_side;

  // `nodes` begins with the C-space's reflex nodes.
  Corners(const ConfigurationSpace& cspace, const std::vector<Point>& nodes);

  // Whether a graph edge from reflex node k to the point at k's node + u
  // can be dropped before its segment test.
  //
  // The obstacle at the node is the wedge between the directions back along
  // the incoming edge and on along the outgoing one (less than 180 degrees:
  // the free space's corner is reflex).
  // - behind: -u inside the wedge (the line runs on behind the node into the
  //   obstacle). A path that bends at the node onto this edge keeps the
  //   obstacle on the outside of the bend and is shortened by cutting the
  //   bend, so the edge is never on a shortest path. This is the classic
  //   rule that a shortest path bends only along lines tangent to the
  //   boundary (both edges on one side of the line).
  // - across: the edge properly crosses one of the node's own two boundary
  //   edges, so the segment test would fail (strict orientation tests:
  //   touching is left to the segment test).
  // The nodes sit interior_offset_m off the vertices, so in the node graph
  // that shortest_paths searches a path may cut a corner by about that
  // much: pass a short boundary edge's far vertex without bending at its
  // node, or bend at a node along a line that runs that little into the
  // wedge behind it. So "inside the wedge" means deeper at a neighbouring
  // vertex (the line's distance from it) than twice the offset of that
  // vertex's own node. (With this slack the matrix equals the full graph's
  // lengths on every random map tried; with none it was up to 3e-5 m
  // longer.)
  //
  // a and b are |u| times how far p and q lie from the line, signed so that
  // both are negative when the wedge lies behind the node. Each condition
  // is written as "max of terms < 0" and the result is their min, so that
  // the loop over all pairs of nodes has no branch, no square root, and
  // vectorises (SSE2 has no conversion of a comparison to an integer).
  double score(std::size_t k, double ux, double uy) const {
    const double a = ux * in_y[k] - uy * in_x[k];
    const double b = ux * out_y[k] - uy * out_x[k];
    const double u2 = ux * ux + uy * uy;
    // behind: a < 0, b < 0, a^2 > slack_p2 u2, b^2 > slack_q2 u2.
    const double behind = std::max(std::max(a, b), std::max(slack_p2[k] * u2 - a * a, slack_q2[k] * u2 - b * b));
    // across edge p-v: orient(n, n + u, p) and orient(n, n + u, v) differ
    // in sign, and n + u is beyond the edge's line: orient(p, v, n + u) =
    // in_side - a < 0. Likewise for edge v-q.
    const double op = ux * pn_y[k] - uy * pn_x[k];
    const double ov = ux * vn_y[k] - uy * vn_x[k];
    const double oq = ux * qn_y[k] - uy * qn_x[k];
    const double across_in = std::max(op * ov, in_side[k] - a);
    const double across_out = std::max(ov * oq, out_side[k] - b);
    return std::min(behind, std::min(across_in, across_out));
  }
  bool drops(std::size_t k, double ux, double uy) const { return score(k, ux, uy) < 0.0; }

  // out[t] < 0: drops() at either end of the edge i-j, for j = first + t,
  // t < count. `out` should be a local array: then the compiler knows it
  // does not alias the corners' arrays, and vectorises (inlined: out of line,
  // `out` may alias them).
  [[gnu::always_inline]] void scores(std::size_t i, std::size_t first, std::size_t count, double* out) const {
    const double xi = x[i], yi = y[i];
    for (std::size_t t = 0; t < count; ++t) {
      const std::size_t j = first + t;
      const double ux = x[j] - xi, uy = y[j] - yi;
      out[t] = std::min(score(i, ux, uy), score(j, -ux, -uy));
    }
  }
};

// Undirected edges, a[k] - b[k] of length[k].
struct EdgeList {
  std::vector<std::uint32_t> a, b;
  std::vector<double> length;
  void add(std::uint32_t u, std::uint32_t v, double l) {
    a.push_back(u);
    b.push_back(v);
    length.push_back(l);
  }
};

// The segment test of the graph: whether the straight segment between two
// nodes stays in the C-space, asked with the ends in one order (x, then y)
// whichever node is which, so that the answer for a pair is the same
// whatever the nodes' indices.
bool nodes_see_each_other(const ConfigurationSpace& cspace, const Point& a, const Point& b);

// The segment tests of the graph over the last C-space, for the next one
// (pruned_graph_edges): a pair of nodes found again (a reflex node with the
// same position and the same five boundary vertices around it, which is all
// its pruning depends on; a point at the same position) keeps the answer
// of its segment test, unless the segment comes near a boundary edge that
// one C-space has and the other has not, where the answer may differ; the
// pairs a node that is new takes part in are scored and tested afresh. So
// the graph is the one built without the cache, edge for edge; a planner
// that replans a map changed near the robot tests a few segments of
// thousands. Where most of the boundary changed (SLAM moved the map) it
// builds the graph afresh. One per planning thread (not thread-safe); it holds one
// C-space's tests, so a thread that alternates between two clearances
// would do well with one per clearance.
class VisibilityCache {
 public:
  struct Counters {
    std::int64_t builds = 0;     // graphs built through the cache
    std::int64_t kept = 0;       // segment tests answered from the last graph
    std::int64_t retested = 0;   // pairs found again whose segment comes near a change
    std::int64_t new_pairs = 0;  // pairs with a new node, tested (after pruning)
    std::int64_t rebuilt = 0;    // graphs built afresh: most of the boundary had changed
    Counters& operator+=(const Counters& o) {
      builds += o.builds, kept += o.kept, retested += o.retested, new_pairs += o.new_pairs, rebuilt += o.rebuilt;
      return *this;
    }
  };
  const Counters& counters() const { return counters_; }

 private:
  friend EdgeList pruned_graph_edges(const ConfigurationSpace&, const std::vector<Point>&, std::uint32_t, bool,
                                     VisibilityCache*);
  // Keys compare the bits of the coordinates: a node is found again only if
  // it is exactly where it was.
  using ReflexKey = std::array<std::uint64_t, 12>;  // node, then p's predecessor, p, v, q, q's successor
  using PointKey = std::array<std::uint64_t, 2>;
  using EdgeKey = std::array<std::uint64_t, 4>;
  struct KeyHash {
    template <std::size_t N>
    std::size_t operator()(const std::array<std::uint64_t, N>& key) const {
      std::uint64_t h = 0x9e3779b97f4a7c15ull;
      for (const auto k : key) h = (h ^ k) * 0x100000001b3ull + (h >> 29);
      return static_cast<std::size_t>(h);
    }
  };
  struct TestedPair {
    std::uint32_t reflex, other;  // node indices of the graph it was built for
    bool free;
  };
  // More than 1 / kMostlyChanged of the boundary's edges changed: the graph
  // is built afresh (and kept for the next).
  static constexpr std::size_t kMostlyChanged = 2;
  // pruned_graph_edges with pruning, through the cache.
  EdgeList graph_edges(const ConfigurationSpace& cspace, const std::vector<Point>& nodes, std::uint32_t r);

  std::unordered_map<ReflexKey, std::uint32_t, KeyHash> reflex_;  // last graph's reflex nodes
  std::unordered_map<PointKey, std::uint32_t, KeyHash> points_;   // ... and its points
  std::uint32_t last_nodes_ = 0;
  std::unordered_set<EdgeKey, KeyHash> boundary_;  // the last C-space's edges
  std::vector<TestedPair> tested_;                  // every pair the pruning let through
  double interior_offset_m_ = -1.0;                 // the nodes' offset (their pruning depends on it)
  Counters counters_;
};

// The graph's edges over `nodes` (reflex nodes 0..r-1, as
// cspace.reflex_nodes(), then the points): with `prune`, reflex pairs worth
// testing at both ends and each point to the reflex nodes worth testing at
// their end; without, every visible reflex pair and point-reflex pair.
// Listed reflex pairs first, each pair by its lower index then the other.
// `cache` (may be null; used with `prune` only) keeps the segment tests for
// the next call; the edges do not depend on it.
EdgeList pruned_graph_edges(const ConfigurationSpace& cspace, const std::vector<Point>& nodes, std::uint32_t r,
                            bool prune, VisibilityCache* cache = nullptr);

}  // namespace pex::planning
