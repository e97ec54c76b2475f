#include "planning/pruned_graph.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <map>
#include <tuple>

namespace pex::planning {

namespace {

// How far ConfigurationSpace moves a node off the vertex at which `edge`
// ends (the miter of the two edges' parallels at interior_offset_m, capped as
// inward() caps it at sharp corners), whether that vertex is reflex or not.
double node_offset(const ConfigurationSpace& cspace, std::uint32_t edge) {
  const auto& in = cspace.edges()[edge];
  const auto& out = cspace.edges()[in.next];
  const double lin = distance(in.a, in.b), lout = distance(out.a, out.b);
  const double nx = -(in.b.y() - in.a.y()) / lin - (out.b.y() - out.a.y()) / lout;
  const double ny = (in.b.x() - in.a.x()) / lin + (out.b.x() - out.a.x()) / lout;
  return cspace.options().interior_offset_m / std::max(std::hypot(nx, ny) / 2.0, 0.1);
}

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

// The boundary edges one C-space has and the other has not, and whether a
// segment comes near one of them. Near: the segment meets the edge's box
// grown by kGrowM (a separating-axis test: the box's two axes and the
// segment's normal). Conservative: a segment the segment test finds meeting
// such an edge meets its box, and its grown box by more than the rounding
// of the test; a segment near but not meeting is only tested once more.
// The edges are grouped by the kClusterM square their first end lies in,
// each group with the box of its edges, so that a segment far from a group
// costs one box test (the changes of a replan lie in a few places).
class BoundaryChanges {
 public:
  void add(const Point& a, const Point& b) {
    const Box box{std::min(a.x(), b.x()) - kGrowM, std::min(a.y(), b.y()) - kGrowM, std::max(a.x(), b.x()) + kGrowM,
                  std::max(a.y(), b.y()) + kGrowM};
    const std::array<std::int64_t, 2> cell{static_cast<std::int64_t>(std::floor(a.x() / kClusterM)),
                                           static_cast<std::int64_t>(std::floor(a.y() / kClusterM))};
    auto [it, added] = cluster_of_.try_emplace(cell, clusters_.size());
    if (added) clusters_.push_back({box, {}});
    Cluster& cluster = clusters_[it->second];
    cluster.box = joined(cluster.box, box);
    cluster.edges.push_back(box);
    all_ = count_ == 0 ? box : joined(all_, box);
    ++count_;
  }
  std::size_t size() const { return count_; }
  bool near(const Point& a, const Point& b) const {
    if (count_ == 0 || !meets(a, b, all_)) return false;
    for (const Cluster& cluster : clusters_)
      if (meets(a, b, cluster.box) &&
          std::any_of(cluster.edges.begin(), cluster.edges.end(), [&](const Box& box) { return meets(a, b, box); }))
        return true;
    return false;
  }

 private:
  static constexpr double kGrowM = 1e-6;
  static constexpr double kClusterM = 4.0;
  struct Box {
    double x0, y0, x1, y1;
  };
  struct Cluster {
    Box box;
    std::vector<Box> edges;
  };
  static Box joined(const Box& u, const Box& v) {
    return {std::min(u.x0, v.x0), std::min(u.y0, v.y0), std::max(u.x1, v.x1), std::max(u.y1, v.y1)};
  }
  static bool meets(const Point& a, const Point& b, const Box& box) {
    if (std::max(a.x(), b.x()) < box.x0 || std::min(a.x(), b.x()) > box.x1 || std::max(a.y(), b.y()) < box.y0 ||
        std::min(a.y(), b.y()) > box.y1)
      return false;
    const double dx = b.x() - a.x(), dy = b.y() - a.y();
    auto side = [&](double x, double y) { return dx * (y - a.y()) - dy * (x - a.x()); };
    const double s00 = side(box.x0, box.y0), s01 = side(box.x0, box.y1);
    const double s10 = side(box.x1, box.y0), s11 = side(box.x1, box.y1);
    return !((s00 > 0 && s01 > 0 && s10 > 0 && s11 > 0) || (s00 < 0 && s01 < 0 && s10 < 0 && s11 < 0));
  }
  std::map<std::array<std::int64_t, 2>, std::size_t> cluster_of_;
  std::vector<Cluster> clusters_;
  Box all_{};
  std::size_t count_ = 0;
};

// An edge as it is listed: (lower node, higher node), or (reflex node,
// point), the order of the graph built without the cache.
struct ListedEdge {
  std::uint32_t a, b;
};

EdgeList edges_in_order(std::vector<ListedEdge> listed, const std::vector<Point>& nodes, std::uint32_t r) {
  std::sort(listed.begin(), listed.end(), [r](const ListedEdge& u, const ListedEdge& v) {
    return std::make_tuple(u.b >= r, u.a, u.b) < std::make_tuple(v.b >= r, v.a, v.b);
  });
  EdgeList edges;
  for (const ListedEdge& e : listed) edges.add(e.a, e.b, distance(nodes[e.a], nodes[e.b]));
  return edges;
}

// The pairs of nodes a graph over `nodes` tests, in the order of the graph
// built without the cache: each reflex pair once (i, j), then each reflex
// node with each point (i, p). With `prune`, a pair the corners drop at
// either end is left out. Only pairs with a node `is_new` marks are visited
// (all of them, without a cache: a pair of nodes found again keeps its
// answer, VisibilityCache). A new reflex node i is paired with every reflex
// node after it and with the nodes found again before it: those before the
// first found again are new and paired with i already. The block loop of
// Corners::scores vectorises here (GCC's choice hung on the callers' code
// once inlined into them: plans 30 % slower at p99 on intel's maps).
template <class IsNew, class Test>
[[gnu::noinline]] void for_each_pair_to_test(const Corners& corners, const std::vector<Point>& nodes, std::uint32_t r,
                                             bool prune, IsNew is_new, Test test) {
  const auto total = static_cast<std::uint32_t>(nodes.size());
  std::uint32_t first_kept = 0;  // the first reflex node found again (r: none)
  while (first_kept < r && is_new(first_kept)) ++first_kept;
  for (std::uint32_t i = 0; i < r; ++i) {
    if (!is_new(i)) continue;
    // The cheap test for a block of j at once (both ends), then the pairs it keeps.
    constexpr std::uint32_t kBlock = 256;
    double score[kBlock];
    for (std::uint32_t first = std::min(first_kept, i + 1); first < r; first += kBlock) {
      const std::uint32_t count = std::min(kBlock, r - first);
      if (prune) corners.scores(i, first, count, score);
      for (std::uint32_t t = 0; t < count; ++t) {
        const std::uint32_t j = first + t;
        if (j == i || (j < i && is_new(j)) || (prune && score[t] < 0.0)) continue;
        test(i, j);
      }
    }
  }
  for (std::uint32_t i = 0; i < r; ++i) {
    for (std::uint32_t p = r; p < total; ++p) {
      if (!is_new(i) && !is_new(p)) continue;
      if (prune && corners.drops(i, nodes[p].x() - nodes[i].x(), nodes[p].y() - nodes[i].y())) continue;
      test(i, p);
    }
  }
}

}  // namespace

Corners::Corners(const ConfigurationSpace& cspace, const std::vector<Point>& nodes) {
  for (std::size_t k = 0; k < cspace.reflex_edges().size(); ++k) {
    const std::uint32_t e = cspace.reflex_edges()[k];
    const auto& in = cspace.edges()[e];
    const auto& out = cspace.edges()[in.next];
    const Point& n = nodes[k];
    x.push_back(n.x());
    y.push_back(n.y());
    in_x.push_back(in.b.x() - in.a.x());
    in_y.push_back(in.b.y() - in.a.y());
    out_x.push_back(out.b.x() - out.a.x());
    out_y.push_back(out.b.y() - out.a.y());
    const double slack_p = 2.0 * node_offset(cspace, in.prev), slack_q = 2.0 * node_offset(cspace, in.next);
    slack_p2.push_back(slack_p * slack_p);
    slack_q2.push_back(slack_q * slack_q);
    pn_x.push_back(in.a.x() - n.x());
    pn_y.push_back(in.a.y() - n.y());
    vn_x.push_back(in.b.x() - n.x());
    vn_y.push_back(in.b.y() - n.y());
    qn_x.push_back(out.b.x() - n.x());
    qn_y.push_back(out.b.y() - n.y());
    in_side.push_back(in_x.back() * -pn_y.back() + in_y.back() * pn_x.back());
    out_side.push_back(out_x.back() * -vn_y.back() + out_y.back() * vn_x.back());
  }
}

bool nodes_see_each_other(const ConfigurationSpace& cspace, const Point& a, const Point& b) {
  const bool in_order = a.x() < b.x() || (a.x() == b.x() && a.y() <= b.y());
  return in_order ? cspace.segment_free(a, b) : cspace.segment_free(b, a);
}

EdgeList VisibilityCache::graph_edges(const ConfigurationSpace& cspace, const std::vector<Point>& nodes,
                                      std::uint32_t r) {
  ++counters_.builds;
  if (cspace.options().interior_offset_m != interior_offset_m_) {
    const Counters counters = counters_;
    *this = VisibilityCache{};  // no answer carries over
    counters_ = counters;
    interior_offset_m_ = cspace.options().interior_offset_m;
  }
  const Corners corners(cspace, nodes);
  const auto total = static_cast<std::uint32_t>(nodes.size());

  // 1. The nodes found again: last[v], the node's index in the last graph
  // (-1: new); now[w], the last graph's node w's index in this one.
  std::vector<std::int64_t> last(total, -1), now(last_nodes_, -1);
  decltype(reflex_) reflex;
  decltype(points_) points;
  reflex.reserve(r);
  points.reserve(total - r);
  const auto& edges = cspace.edges();
  for (std::uint32_t k = 0; k < r; ++k) {
    const auto& in = edges[cspace.reflex_edges()[k]];
    const auto& out = edges[in.next];
    const Point& before = edges[in.prev].a;
    const Point& after = edges[out.next].b;
    const ReflexKey key{bits(nodes[k].x()), bits(nodes[k].y()), bits(before.x()), bits(before.y()),
                        bits(in.a.x()),     bits(in.a.y()),     bits(in.b.x()),   bits(in.b.y()),
                        bits(out.b.x()),    bits(out.b.y()),    bits(after.x()),  bits(after.y())};
    reflex.emplace(key, k);
    const auto found = reflex_.find(key);
    if (found != reflex_.end() && now[found->second] < 0) last[k] = found->second, now[found->second] = k;
  }
  for (std::uint32_t p = r; p < total; ++p) {
    const PointKey key{bits(nodes[p].x()), bits(nodes[p].y())};
    points.emplace(key, p);
    const auto found = points_.find(key);
    if (found != points_.end() && now[found->second] < 0) last[p] = found->second, now[found->second] = p;
  }

  // 2. What changed on the boundary.
  decltype(boundary_) boundary;
  boundary.reserve(edges.size());
  BoundaryChanges changes;
  for (const auto& e : edges) {
    const EdgeKey key{bits(e.a.x()), bits(e.a.y()), bits(e.b.x()), bits(e.b.y())};
    boundary.insert(key);
    if (!boundary_.contains(key)) changes.add(e.a, e.b);
  }
  for (const EdgeKey& key : boundary_)
    if (!boundary.contains(key))
      changes.add(Point(std::bit_cast<double>(key[0]), std::bit_cast<double>(key[1])),
                  Point(std::bit_cast<double>(key[2]), std::bit_cast<double>(key[3])));

  // Where much of the boundary changed (SLAM moved the map), most pairs
  // would be tested again, and each against many changes: every node counts
  // as new, which costs what the graph costs without the cache.
  if (changes.size() > edges.size() / kMostlyChanged) {
    std::fill(last.begin(), last.end(), -1);
    std::fill(now.begin(), now.end(), -1);
    ++counters_.rebuilt;
  }

  // 3. The pairs of nodes found again that the pruning let through last
  // time: the same answer unless near a change. (A pair of such nodes not
  // listed was pruned, and is again: the pruning depends on the key alone.)
  std::vector<TestedPair> tested;
  tested.reserve(tested_.size());
  for (const TestedPair& pair : tested_) {
    const std::int64_t i = now[pair.reflex], j = now[pair.other];
    if (i < 0 || j < 0) continue;
    const auto u = static_cast<std::uint32_t>(i), v = static_cast<std::uint32_t>(j);
    bool free = pair.free;
    if (changes.near(nodes[u], nodes[v])) {
      free = nodes_see_each_other(cspace, nodes[u], nodes[v]);
      ++counters_.retested;
    } else {
      ++counters_.kept;
    }
    tested.push_back({u, v, free});
  }

  // 4. The pairs with a new node, pruned and tested as without the cache.
  for_each_pair_to_test(
      corners, nodes, r, true, [&](std::uint32_t v) { return last[v] < 0; },
      [&](std::uint32_t reflex_node, std::uint32_t other) {
        tested.push_back({reflex_node, other, nodes_see_each_other(cspace, nodes[reflex_node], nodes[other])});
        ++counters_.new_pairs;
      });

  std::vector<ListedEdge> listed;
  for (const TestedPair& pair : tested) {
    if (!pair.free) continue;
    if (pair.other < r)
      listed.push_back({std::min(pair.reflex, pair.other), std::max(pair.reflex, pair.other)});
    else
      listed.push_back({pair.reflex, pair.other});
  }
  reflex_ = std::move(reflex);
  points_ = std::move(points);
  last_nodes_ = total;
  boundary_ = std::move(boundary);
  tested_ = std::move(tested);
  return edges_in_order(std::move(listed), nodes, r);
}

EdgeList pruned_graph_edges(const ConfigurationSpace& cspace, const std::vector<Point>& nodes, std::uint32_t r,
                            bool prune, VisibilityCache* cache) {
  if (cache && prune) return cache->graph_edges(cspace, nodes, r);
  EdgeList edges;
  for_each_pair_to_test(
      Corners(cspace, nodes), nodes, r, prune, [](std::uint32_t) { return true; },
      [&](std::uint32_t i, std::uint32_t j) {
        if (nodes_see_each_other(cspace, nodes[i], nodes[j])) edges.add(i, j, distance(nodes[i], nodes[j]));
      });
  return edges;
}

}  // namespace pex::planning
