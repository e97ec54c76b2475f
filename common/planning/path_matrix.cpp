#include "planning/path_matrix.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <utility>

namespace pex::planning {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// std::hypot is several times slower and needs no guard here (map coordinates).
double length(const Point& a, const Point& b) {
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  return std::sqrt(dx * dx + dy * dy);
}

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
// over all of them for each node): per node its vertex v, the neighbours p
// (before) and q (after), the edge vectors v - p ("in") and q - v ("out"),
// and slack_p2 / slack_q2, the squares of how deep a line through the node
// may pass beyond p or q and still be on a shortest path of the node graph
// (see below). The node is v moved interior_offset_m inward with both edges
// kept parallel, so the edge vectors are also the directions of the
// boundary moved to the node.
struct Corners {
  std::vector<double> x, y;  // the node
  std::vector<double> in_x, in_y, out_x, out_y;
  std::vector<double> slack_p2, slack_q2;
  std::vector<Point> p, v, q;

  Corners(const ConfigurationSpace& cspace, const std::vector<Point>& nodes) {
    for (std::size_t k = 0; k < cspace.reflex_edges().size(); ++k) {
      const std::uint32_t e = cspace.reflex_edges()[k];
      const auto& in = cspace.edges()[e];
      const auto& out = cspace.edges()[in.next];
      x.push_back(nodes[k].x());
      y.push_back(nodes[k].y());
      in_x.push_back(in.b.x() - in.a.x());
      in_y.push_back(in.b.y() - in.a.y());
      out_x.push_back(out.b.x() - out.a.x());
      out_y.push_back(out.b.y() - out.a.y());
      const double slack_p = 2.0 * node_offset(cspace, in.prev), slack_q = 2.0 * node_offset(cspace, in.next);
      slack_p2.push_back(slack_p * slack_p);
      slack_q2.push_back(slack_q * slack_q);
      p.push_back(in.a);
      v.push_back(in.b);
      q.push_back(out.b);
    }
  }

  // Which graph edges from reflex node k, in direction (ux, uy), are worth
  // a segment test.
  //
  // The obstacle at the node is the wedge between the directions back along
  // the incoming edge and on along the outgoing one (less than 180 degrees:
  // the free space's corner is reflex).
  // - behind(): -u inside the wedge (the line runs on behind the node into
  //   the obstacle). A path that bends at the node onto this edge keeps the
  //   obstacle on the outside of the bend and is shortened by cutting the
  //   bend, so the edge is never on a shortest path. This is most of the
  //   pruning: the classic rule that a shortest path bends only along lines
  //   tangent to the boundary (both edges on one side of the line).
  // - blocked_here(): u inside the wedge and the edge crosses one of the
  //   node's own two boundary edges (exact; no index needed).
  // - otherwise (tangent, or into the wedge but not across those two
  //   edges): tested.
  // The nodes sit interior_offset_m off the vertices, so in the node graph
  // that shortest_paths searches a path may cut a corner by about that
  // much: pass a short boundary edge's far vertex without bending at its
  // node, or bend at a node along a line that runs that little into the
  // wedge behind it. So "inside the wedge" in behind() means deeper at a
  // neighbouring vertex (the line's distance from it) than twice the offset
  // of that vertex's own node. (With this slack the matrix equals the full
  // graph's lengths on every random map tried; with none it was up to
  // 3e-5 m longer.)
  //
  // a and b are |u| times how far p and q lie from the line, signed so that
  // both are negative when the wedge lies behind the node, both positive
  // when ahead; no square root, and no branch, for the pair loop.
  bool behind(std::size_t k, double ux, double uy) const {
    const double a = ux * in_y[k] - uy * in_x[k];
    const double b = ux * out_y[k] - uy * out_x[k];
    const double u2 = ux * ux + uy * uy;
    return (a < 0.0) & (b < 0.0) & (a * a > slack_p2[k] * u2) & (b * b > slack_q2[k] * u2);
  }
  bool blocked_here(std::size_t k, const Point& node, const Point& other) const {
    const double ux = other.x() - node.x(), uy = other.y() - node.y();
    const double a = ux * in_y[k] - uy * in_x[k];
    const double b = ux * out_y[k] - uy * out_x[k];
    return a > 0.0 && b > 0.0 &&
           (segments_intersect(node, other, p[k], v[k]) || segments_intersect(node, other, v[k], q[k]));
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

// Dijkstra from `source` until every node >= `first_wanted` is settled (or
// nothing is left). Nodes >= `first_point` are path ends: they are settled
// but never relaxed from, except the source. `dist`, `parent`, `settled`
// must be +inf / -1 / 0 on entry; `touched` lists what was set, for a cheap
// reset.
void dijkstra(const Graph& g, std::uint32_t source, std::uint32_t first_point, std::uint32_t first_wanted,
              std::vector<double>& dist, std::vector<std::int32_t>& parent, std::vector<char>& settled,
              std::vector<std::uint32_t>& touched) {
  using Entry = std::pair<double, std::uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  const auto nodes = static_cast<std::uint32_t>(g.offset.size() - 1);
  std::uint32_t wanted_left = nodes - std::min(first_wanted, nodes);
  dist[source] = 0.0;
  touched.push_back(source);
  queue.emplace(0.0, source);
  while (!queue.empty() && wanted_left > 0) {
    const auto [d, u] = queue.top();
    queue.pop();
    if (settled[u]) continue;
    settled[u] = 1;
    if (u >= first_wanted) --wanted_left;
    if (u >= first_point && u != source) continue;
    for (std::uint32_t k = g.offset[u]; k < g.offset[u + 1]; ++k) {
      const std::uint32_t v = g.to[k];
      const double candidate = d + g.length[k];
      if (settled[v] || !(candidate < dist[v])) continue;
      if (dist[v] == kInf) touched.push_back(v);
      dist[v] = candidate;
      parent[v] = static_cast<std::int32_t>(u);
      queue.emplace(candidate, v);
    }
  }
}

}  // namespace

PathMatrix shortest_path_matrix(const ConfigurationSpace& cspace, const Point& start,
                                const std::vector<Point>& targets, const PathMatrixOptions& options) {
  const std::int64_t tests_before = cspace.segment_tests();
  const auto& reflex = cspace.reflex_nodes();
  const auto r = static_cast<std::uint32_t>(reflex.size());
  const std::size_t n = targets.size();
  // Nodes 0..r-1: reflex vertices; r: the start; r + 1 + i: target i.
  std::vector<Point> nodes(reflex.begin(), reflex.end());
  nodes.push_back(start);
  nodes.insert(nodes.end(), targets.begin(), targets.end());
  const std::uint32_t first_point = r;
  const auto total = static_cast<std::uint32_t>(nodes.size());

  const Corners corners(cspace, nodes);
  const bool prune = options.tangent_pruning;

  // 1. The graph: reflex-reflex edges worth testing at both ends, then each
  // point to the reflex vertices it sees, worth testing at the reflex end.
  // No point-point edges: a path between points that bends, bends at reflex
  // vertices only.
  EdgeList edges;
  std::vector<char> drop(r);
  for (std::uint32_t i = 0; i < r; ++i) {
    // The cheap test for all j > i at once (both ends), then the rest.
    const double xi = corners.x[i], yi = corners.y[i];
    for (std::uint32_t j = i + 1; j < r; ++j) {
      const double ux = corners.x[j] - xi, uy = corners.y[j] - yi;
      drop[j] = prune & (corners.behind(i, ux, uy) | corners.behind(j, -ux, -uy));
    }
    for (std::uint32_t j = i + 1; j < r; ++j) {
      if (drop[j]) continue;
      if (prune && (corners.blocked_here(i, nodes[i], nodes[j]) || corners.blocked_here(j, nodes[j], nodes[i])))
        continue;
      if (!cspace.segment_free(nodes[i], nodes[j])) continue;
      edges.add(i, j, length(nodes[i], nodes[j]));
    }
  }
  for (std::uint32_t i = 0; i < r; ++i) {
    for (std::uint32_t p = first_point; p < total; ++p) {
      if (prune && (corners.behind(i, nodes[p].x() - nodes[i].x(), nodes[p].y() - nodes[i].y()) ||
                    corners.blocked_here(i, nodes[i], nodes[p])))
        continue;
      if (!cspace.segment_free(nodes[i], nodes[p])) continue;
      edges.add(i, p, length(nodes[i], nodes[p]));
    }
  }
  const Graph graph = compress(edges, total);

  // 2. One Dijkstra per point, for the points after it; then the straight
  // segment wherever it would be shorter than the bending path.
  PathMatrix out;
  out.from_start_m.assign(n, kInf);
  out.path_from_start.resize(n);
  out.between_m.assign(n * n, kInf);
  for (std::size_t i = 0; i < n; ++i) out.between_m[i * n + i] = 0.0;
  std::vector<double> dist(total, kInf);
  std::vector<std::int32_t> parent(total, -1);
  std::vector<char> settled(total, 0);
  std::vector<std::uint32_t> touched;
  for (std::uint32_t p = first_point; p + 1 < total; ++p) {
    dijkstra(graph, p, first_point, p + 1, dist, parent, settled, touched);
    for (std::uint32_t q = p + 1; q < total; ++q) {
      double d = dist[q];
      bool straight = false;
      const double direct = length(nodes[p], nodes[q]);
      if (direct < d && cspace.segment_free(nodes[p], nodes[q])) {
        d = direct;
        straight = true;
      }
      const std::size_t tq = q - first_point - 1;
      if (p == first_point) {
        out.from_start_m[tq] = d;
        if (d == kInf) continue;
        std::vector<Point>& path = out.path_from_start[tq];
        path.push_back(nodes[q]);
        if (!straight)
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

}  // namespace pex::planning
