#include "planning/path_matrix.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace pex::planning {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

// The boundary at the reflex nodes, as arrays (the pair loop below runs
// over all of them for each node): per node n its vertex v, the neighbours p
// (before) and q (after), the edge vectors v - p ("in") and q - v ("out"),
// and slack_p2 / slack_q2, the squares of how deep a line through the node
// may pass beyond p or q and still be on a shortest path of the node graph
// (see drops()). The node is v moved interior_offset_m inward with both
// edges kept parallel, so the edge vectors are also the directions of the
// boundary moved to the node.
struct Corners {
  std::vector<double> x, y;  // the node
  std::vector<double> in_x, in_y, out_x, out_y;
  std::vector<double> slack_p2, slack_q2;
  // p - n, v - n, q - n; and orient(p, v, n), orient(v, q, n), both > 0
  // (the node is on the free side, the left, of both edges).
  std::vector<double> pn_x, pn_y, vn_x, vn_y, qn_x, qn_y, in_side, out_side;

  Corners(const ConfigurationSpace& cspace, const std::vector<Point>& nodes) {
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
  // does not alias the corners' arrays, and vectorises.
  void scores(std::size_t i, std::size_t first, std::size_t count, double* out) const {
    const double xi = x[i], yi = y[i];
    for (std::size_t t = 0; t < count; ++t) {
      const std::size_t j = first + t;
      const double ux = x[j] - xi, uy = y[j] - yi;
      out[t] = std::min(score(i, ux, uy), score(j, -ux, -uy));
    }
  }
};

// Compressed adjacency lists of an undirected graph.
struct Graph {
  std::vector<std::uint32_t> offset;  // node v's edges: [offset[v], offset[v + 1])
  std::vector<std::uint32_t> to;
  std::vector<double> length;
};

struct EdgeList {
  std::vector<std::uint32_t> a, b;
  std::vector<double> length;
  void add(std::uint32_t u, std::uint32_t v, double l) {
    a.push_back(u);
    b.push_back(v);
    length.push_back(l);
  }
};

Graph compress(const EdgeList& edges, std::size_t nodes) {
  Graph g;
  g.offset.assign(nodes + 1, 0);
  for (std::size_t e = 0; e < edges.a.size(); ++e) {
    ++g.offset[edges.a[e] + 1];
    ++g.offset[edges.b[e] + 1];
  }
  for (std::size_t v = 0; v < nodes; ++v) g.offset[v + 1] += g.offset[v];
  g.to.resize(2 * edges.a.size());
  g.length.resize(2 * edges.a.size());
  std::vector<std::uint32_t> fill(g.offset.begin(), g.offset.end() - 1);
  for (std::size_t e = 0; e < edges.a.size(); ++e) {
    g.to[fill[edges.a[e]]] = edges.b[e];
    g.length[fill[edges.a[e]]++] = edges.length[e];
    g.to[fill[edges.b[e]]] = edges.a[e];
    g.length[fill[edges.b[e]]++] = edges.length[e];
  }
  return g;
}

// A 4-ary min-heap of node ids keyed by a vector of the caller's (dist[] in
// Dijkstra, dist + a lower bound in A*; ties: lower id first), with
// decrease-key: each node is in it at most once, so a search pops each node
// once (a heap of (distance, node) pairs with lazy deletion pops every
// improvement, about three times as many, and the pops were most of the
// matrix's time).
class NodeHeap {
 public:
  explicit NodeHeap(std::size_t nodes) : position_(nodes, kAbsent) {}

  bool empty() const { return heap_.empty(); }
  // Inserts v or moves it up after dist[v] decreased.
  void push_or_decrease(std::uint32_t v, const std::vector<double>& dist) {
    std::size_t i = position_[v];
    if (i == kAbsent) {
      i = heap_.size();
      heap_.push_back(v);
    }
    while (i > 0) {
      const std::size_t up = (i - 1) / 4;
      if (!less(v, heap_[up], dist)) break;
      place(heap_[up], i);
      i = up;
    }
    place(v, i);
  }
  std::uint32_t pop(const std::vector<double>& dist) {
    const std::uint32_t top = heap_.front();
    position_[top] = kAbsent;
    const std::uint32_t last = heap_.back();
    heap_.pop_back();
    if (heap_.empty()) return top;
    std::size_t i = 0;
    for (;;) {
      const std::size_t first_child = 4 * i + 1;
      if (first_child >= heap_.size()) break;
      std::size_t best = first_child;
      const std::size_t end = std::min(first_child + 4, heap_.size());
      for (std::size_t c = first_child + 1; c < end; ++c)
        if (less(heap_[c], heap_[best], dist)) best = c;
      if (!less(heap_[best], last, dist)) break;
      place(heap_[best], i);
      i = best;
    }
    place(last, i);
    return top;
  }

 private:
  static constexpr std::size_t kAbsent = static_cast<std::size_t>(-1);
  static bool less(std::uint32_t a, std::uint32_t b, const std::vector<double>& dist) {
    return dist[a] < dist[b] || (dist[a] == dist[b] && a < b);
  }
  void place(std::uint32_t v, std::size_t i) {
    heap_[i] = v;
    position_[v] = i;
  }
  std::vector<std::uint32_t> heap_;
  std::vector<std::size_t> position_;
};

// Dijkstra from `source` until every node marked `wanted` (there are
// `wanted_left`) is settled, or nothing is left. Nodes >= `first_point` are
// path ends: they are settled but never relaxed from, except the source.
// `dist`, `parent`, `settled` must be +inf / -1 / 0 on entry and `heap`
// empty; `touched` lists what was set, for a cheap reset.
void dijkstra(const Graph& g, std::uint32_t source, std::uint32_t first_point, const std::vector<char>& wanted,
              std::uint32_t wanted_left, std::vector<double>& dist, std::vector<std::int32_t>& parent,
              std::vector<char>& settled, std::vector<std::uint32_t>& touched, NodeHeap& heap) {
  dist[source] = 0.0;
  touched.push_back(source);
  heap.push_or_decrease(source, dist);
  while (!heap.empty() && wanted_left > 0) {
    const std::uint32_t u = heap.pop(dist);
    settled[u] = 1;
    if (wanted[u]) --wanted_left;
    if (u >= first_point && u != source) continue;
    const double d = dist[u];
    for (std::uint32_t k = g.offset[u]; k < g.offset[u + 1]; ++k) {
      const std::uint32_t v = g.to[k];
      const double candidate = d + g.length[k];
      if (settled[v] || !(candidate < dist[v])) continue;
      if (dist[v] == kInf) touched.push_back(v);
      dist[v] = candidate;
      parent[v] = static_cast<std::int32_t>(u);
      heap.push_or_decrease(v, dist);
    }
  }
  while (!heap.empty()) heap.pop(dist);
}

// The graph's nodes: 0..r-1 the reflex vertices, r the start, r + 1 + i target i.
std::vector<Point> graph_nodes(const ConfigurationSpace& cspace, const Point& start,
                               const std::vector<Point>& targets) {
  const auto& reflex = cspace.reflex_nodes();
  std::vector<Point> nodes(reflex.begin(), reflex.end());
  nodes.push_back(start);
  nodes.insert(nodes.end(), targets.begin(), targets.end());
  return nodes;
}

}  // namespace

PathMatrix shortest_path_matrix(const ConfigurationSpace& cspace, const Point& start,
                                const std::vector<Point>& targets, const PathMatrixOptions& options) {
  const std::int64_t tests_before = cspace.segment_tests();
  const auto r = static_cast<std::uint32_t>(cspace.reflex_nodes().size());
  const std::size_t n = targets.size();
  const std::vector<Point> nodes = graph_nodes(cspace, start, targets);
  const std::uint32_t first_point = r;
  const auto total = static_cast<std::uint32_t>(nodes.size());

  const Corners corners(cspace, nodes);
  const bool prune = options.tangent_pruning;

  // 1. The graph: reflex-reflex edges worth testing at both ends, then each
  // point to the reflex vertices it sees, worth testing at the reflex end.
  // No point-point edges: a path between points that bends, bends at reflex
  // vertices only.
  EdgeList edges;
  for (std::uint32_t i = 0; i < r; ++i) {
    // The cheap test for a block of j > i at once (both ends), then segment
    // tests for what it keeps.
    constexpr std::uint32_t kBlock = 256;
    double score[kBlock];
    for (std::uint32_t first = i + 1; first < r; first += kBlock) {
      const std::uint32_t count = std::min(kBlock, r - first);
      if (prune) corners.scores(i, first, count, score);
      for (std::uint32_t t = 0; t < count; ++t) {
        const std::uint32_t j = first + t;
        if ((prune && score[t] < 0.0) || !cspace.segment_free(nodes[i], nodes[j])) continue;
        edges.add(i, j, distance(nodes[i], nodes[j]));
      }
    }
  }
  for (std::uint32_t i = 0; i < r; ++i) {
    for (std::uint32_t p = first_point; p < total; ++p) {
      if (prune && corners.drops(i, nodes[p].x() - nodes[i].x(), nodes[p].y() - nodes[i].y())) continue;
      if (!cspace.segment_free(nodes[i], nodes[p])) continue;
      edges.add(i, p, distance(nodes[i], nodes[p]));
    }
  }
  const Graph graph = compress(edges, total);

  // 2. From each point to the points after it: the straight segment where
  // it is free, else one Dijkstra for all the others. In open space most
  // pairs see each other and the search stops early or is not needed.
  PathMatrix out;
  out.from_start_m.assign(n, kInf);
  out.path_from_start.resize(n);
  if (options.between_targets) {
    out.between_m.assign(n * n, kInf);
    for (std::size_t i = 0; i < n; ++i) out.between_m[i * n + i] = 0.0;
  }
  std::vector<double> dist(total, kInf);
  std::vector<std::int32_t> parent(total, -1);
  std::vector<char> settled(total, 0), wanted(total, 0), straight(total, 0);
  std::vector<std::uint32_t> touched;
  NodeHeap heap(total);
  const std::uint32_t sources_end = options.between_targets ? total - 1 : std::min(total - 1, first_point + 1);
  for (std::uint32_t p = first_point; p < sources_end; ++p) {
    std::uint32_t wanted_count = 0;
    for (std::uint32_t q = first_point; q < total; ++q) {
      straight[q] = q > p && cspace.segment_free(nodes[p], nodes[q]);
      wanted[q] = q > p && !straight[q];
      wanted_count += wanted[q];
    }
    if (wanted_count > 0) dijkstra(graph, p, first_point, wanted, wanted_count, dist, parent, settled, touched, heap);
    for (std::uint32_t q = p + 1; q < total; ++q) {
      const double d = straight[q] ? distance(nodes[p], nodes[q]) : dist[q];
      const std::size_t tq = q - first_point - 1;
      if (p == first_point) {
        out.from_start_m[tq] = d;
        if (d == kInf) continue;
        std::vector<Point>& path = out.path_from_start[tq];
        path.push_back(nodes[q]);
        if (!straight[q])
          for (std::int32_t v = parent[q]; v >= 0; v = parent[static_cast<std::size_t>(v)])
            path.push_back(nodes[static_cast<std::size_t>(v)]);
        else
          path.push_back(nodes[p]);
        std::reverse(path.begin(), path.end());
      } else {
        const std::size_t tp = p - first_point - 1;
        out.between_m[tp * n + tq] = d;
        out.between_m[tq * n + tp] = d;
      }
    }
    for (const auto v : touched) {
      dist[v] = kInf;
      parent[v] = -1;
      settled[v] = 0;
    }
    touched.clear();
  }

  out.reflex_nodes = r;
  out.graph_edges = static_cast<std::int64_t>(edges.a.size());
  out.segment_tests = cspace.segment_tests() - tests_before;
  return out;
}

PathMatrix shortest_paths_to_cheapest(const ConfigurationSpace& cspace, const Point& start,
                                      const std::vector<Point>& targets, const CheapestTargetQuery& query) {
  const std::int64_t tests_before = cspace.segment_tests();
  const auto r = static_cast<std::uint32_t>(cspace.reflex_nodes().size());
  const std::size_t n = targets.size();
  const std::vector<Point> nodes = graph_nodes(cspace, start, targets);
  const std::uint32_t source = r;
  const auto total = static_cast<std::uint32_t>(nodes.size());
  const Corners corners(cspace, nodes);

  PathMatrix out;
  out.from_start_m.assign(n, kInf);
  out.path_from_start.resize(n);
  out.reflex_nodes = r;
  std::vector<double> dist(total, kInf);
  std::vector<std::int32_t> parent(total, -1);
  std::vector<char> settled(total, 0);
  std::size_t required_left = 0;
  for (const char q : query.required) required_left += q != 0;
  // A*: the heap's key is dist + the straight-line distance to the nearest
  // target that may be chosen or is required, a lower bound on what is left
  // of any path to such a target, and consistent (edges are straight), so a
  // node's distance is final when it is popped, as in Dijkstra. A far goal
  // is searched along the way to it, not in a disc around the robot.
  std::vector<Point> aims;
  for (std::size_t t = 0; t < n; ++t) {
    const bool required = t < query.required.size() && query.required[t];
    const bool choice = query.choice.empty() || (t < query.choice.size() && query.choice[t]);
    if (required || choice) aims.push_back(targets[t]);
  }
  std::vector<double> key(total, kInf), aim_distance(total, -1.0);
  auto lower_bound_left = [&](std::uint32_t v) {
    if (aim_distance[v] < 0.0) {
      double least = aims.empty() ? 0.0 : kInf;
      for (const Point& a : aims) least = std::min(least, distance(nodes[v], a));
      aim_distance[v] = least;
    }
    return aim_distance[v];
  };
  double best_cost = kInf;
  NodeHeap heap(total);
  dist[source] = 0.0;
  key[source] = lower_bound_left(source);
  heap.push_or_decrease(source, key);
  while (!heap.empty()) {
    const std::uint32_t u = heap.pop(key);
    const double d = dist[u];
    // Every path to a target through what is left costs at least key[u].
    if (required_left == 0 && key[u] > best_cost) {
      out.all_searched = false;
      break;
    }
    settled[u] = 1;
    if (u > source) {  // a target: a path end
      const std::size_t t = u - source - 1;
      std::vector<Point>& path = out.path_from_start[t];
      for (std::int32_t v = static_cast<std::int32_t>(u); v >= 0; v = parent[static_cast<std::size_t>(v)])
        path.push_back(nodes[static_cast<std::size_t>(v)]);
      std::reverse(path.begin(), path.end());
      out.from_start_m[t] = d;
      if (t < query.required.size() && query.required[t]) --required_left;
      best_cost = std::min(best_cost, query.cost(t, d, path));
      continue;
    }
    // The edges shortest_path_matrix would keep: reflex-reflex pruned at both
    // ends, start-reflex and reflex-target at the reflex end, start-target straight.
    for (std::uint32_t v = 0; v < total; ++v) {
      if (settled[v] || v == u) continue;
      const double ux = nodes[v].x() - nodes[u].x(), uy = nodes[v].y() - nodes[u].y();
      const double candidate = d + std::sqrt(ux * ux + uy * uy);
      if (!(candidate < dist[v])) continue;
      if (u < r && corners.drops(u, ux, uy)) continue;
      if (v < r && corners.drops(v, -ux, -uy)) continue;
      if (!cspace.segment_free(nodes[u], nodes[v])) continue;
      dist[v] = candidate;
      key[v] = candidate + lower_bound_left(v);
      parent[v] = static_cast<std::int32_t>(u);
      heap.push_or_decrease(v, key);
    }
  }
  out.segment_tests = cspace.segment_tests() - tests_before;
  return out;
}

}  // namespace pex::planning
