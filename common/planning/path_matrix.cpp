#include "planning/path_matrix.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "planning/pruned_graph.hpp"

namespace pex::planning {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Compressed adjacency lists of an undirected graph.
struct Graph {
  std::vector<std::uint32_t> offset;  // node v's edges: [offset[v], offset[v + 1])
  std::vector<std::uint32_t> to;
  std::vector<double> length;
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

// The lazy queries' per-target marks (CheapestTargetQuery,
// NearestTargetsQuery): `choice` empty means every target; `required` empty
// none. The aims of their A*: the targets that are either.
bool is_choice(const std::vector<char>& choice, std::size_t t) {
  return choice.empty() || (t < choice.size() && choice[t]);
}
bool is_required(const std::vector<char>& required, std::size_t t) {
  return t < required.size() && required[t] != 0;
}
// How many targets are required, and how many may be chosen.
struct WantedTargets {
  std::size_t required = 0, choices = 0;
};
WantedTargets count_wanted(std::size_t n, const std::vector<char>& choice, const std::vector<char>& required) {
  WantedTargets w;
  for (std::size_t t = 0; t < n; ++t) {
    w.required += is_required(required, t);
    w.choices += is_choice(choice, t);
  }
  return w;
}
std::vector<Point> search_aims(const std::vector<Point>& targets, const std::vector<char>& choice,
                               const std::vector<char>& required) {
  std::vector<Point> aims;
  for (std::size_t t = 0; t < targets.size(); ++t)
    if (is_required(required, t) || is_choice(choice, t)) aims.push_back(targets[t]);
  return aims;
}

// The `count` choice targets nearest by length (finite only), nearest first;
// ties as a search breaks them: the lower index first.
std::vector<int> nearest_by_length(const std::vector<double>& length_m, const std::vector<char>& choice,
                                   std::size_t count) {
  std::vector<int> by_length;
  for (std::size_t t = 0; t < length_m.size(); ++t)
    if (is_choice(choice, t) && length_m[t] < kInf) by_length.push_back(static_cast<int>(t));
  std::stable_sort(by_length.begin(), by_length.end(), [&](int a, int b) {
    return length_m[static_cast<std::size_t>(a)] < length_m[static_cast<std::size_t>(b)];
  });
  if (by_length.size() > count) by_length.resize(count);
  return by_length;
}

// Length of the part two paths from the same start share (the same nodes,
// the same order).
double shared_length(const std::vector<Point>& a, const std::vector<Point>& b) {
  double length = 0.0;
  for (std::size_t k = 1; k < std::min(a.size(), b.size()); ++k) {
    if (a[k].x() != b[k].x() || a[k].y() != b[k].y()) break;
    length += distance(a[k - 1], a[k]);
  }
  return length;
}

// The first `count` of the graph's nodes in square cells, for the nodes
// within a distance of a point without a loop over all of them (about four
// nodes a cell).
class NodeGrid {
 public:
  NodeGrid(const std::vector<Point>& all_nodes, std::size_t count)
      : nodes_(all_nodes.begin(), all_nodes.begin() + static_cast<std::ptrdiff_t>(count)) {
    const std::vector<Point>& nodes = nodes_;
    if (nodes.empty()) return;
    double max_x = nodes[0].x(), max_y = nodes[0].y();
    min_x_ = max_x, min_y_ = max_y;
    for (const Point& p : nodes) {
      min_x_ = std::min(min_x_, p.x()), min_y_ = std::min(min_y_, p.y());
      max_x = std::max(max_x, p.x()), max_y = std::max(max_y, p.y());
    }
    const double w = max_x - min_x_, h = max_y - min_y_;
    cell_m_ = std::max(std::sqrt(std::max(w * h, 1e-6) * 4.0 / static_cast<double>(nodes.size())), 1e-3);
    cols_ = static_cast<std::int64_t>(w / cell_m_) + 1;
    rows_ = static_cast<std::int64_t>(h / cell_m_) + 1;
    // Cells do not outnumber the nodes by much even for a thin spread of nodes.
    while (cols_ * rows_ > 4 * static_cast<std::int64_t>(nodes.size()) + 16) {
      cell_m_ *= 2.0;
      cols_ = static_cast<std::int64_t>(w / cell_m_) + 1;
      rows_ = static_cast<std::int64_t>(h / cell_m_) + 1;
    }
    first_.assign(static_cast<std::size_t>(cols_ * rows_) + 1, 0);
    for (const Point& p : nodes) ++first_[cell_of(p) + 1];
    for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
    ids_.resize(nodes.size());
    std::vector<std::uint32_t> fill(first_.begin(), first_.end() - 1);
    for (std::uint32_t v = 0; v < nodes.size(); ++v) ids_[fill[cell_of(nodes[v])]++] = v;
  }

  // f(v) for every node v within `radius` of p, and maybe a few beyond.
  template <class F>
  void for_each_within(const Point& p, double radius, F&& f) const {
    if (!(radius >= 0.0)) return;
    const auto clamp_col = [&](double x) {
      return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((x - min_x_) / cell_m_)), 0, cols_ - 1);
    };
    const auto clamp_row = [&](double y) {
      return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((y - min_y_) / cell_m_)), 0, rows_ - 1);
    };
    if (ids_.empty() || p.x() + radius < min_x_ || p.y() + radius < min_y_) return;
    const std::int64_t c0 = clamp_col(p.x() - radius), c1 = clamp_col(p.x() + radius);
    const std::int64_t r0 = clamp_row(p.y() - radius), r1 = clamp_row(p.y() + radius);
    const double r2 = radius * radius;
    for (std::int64_t row = r0; row <= r1; ++row) {
      const auto begin = first_[static_cast<std::size_t>(row * cols_ + c0)];
      const auto end = first_[static_cast<std::size_t>(row * cols_ + c1) + 1];
      for (auto k = begin; k < end; ++k) {
        const std::uint32_t v = ids_[k];
        const double dx = nodes_[v].x() - p.x(), dy = nodes_[v].y() - p.y();
        if (dx * dx + dy * dy <= r2) f(v);
      }
    }
  }

 private:
  std::size_t cell_of(const Point& p) const {
    const auto c = std::min(static_cast<std::int64_t>((p.x() - min_x_) / cell_m_), cols_ - 1);
    const auto r = std::min(static_cast<std::int64_t>((p.y() - min_y_) / cell_m_), rows_ - 1);
    return static_cast<std::size_t>(r * cols_ + c);
  }

  const std::vector<Point> nodes_;
  double min_x_ = 0.0, min_y_ = 0.0, cell_m_ = 1.0;
  std::int64_t cols_ = 1, rows_ = 1;
  std::vector<std::uint32_t> first_;  // cell c's nodes: ids_[first_[c], first_[c + 1])
  std::vector<std::uint32_t> ids_;
};

// The graph of shortest_path_matrix (same pruning, same lengths) searched
// lazily: a node's edges are tested when it is settled, and only those that
// would improve a tentative distance. A*, with the straight-line distance to
// the nearest of the aims as the lower bound: consistent (edges are
// straight), so a node's distance is final when it is popped, as in
// Dijkstra, and the aims are popped in the order of their distances. Nodes
// from r on (the start, the targets) are path ends: settled, never relaxed
// from, except the source.
class LazySearch {
 public:
  LazySearch(const ConfigurationSpace& cspace, std::vector<Point> nodes, std::uint32_t reflex)
      : cspace_(cspace),
        nodes_(std::move(nodes)),
        r_(reflex),
        corners_(cspace, nodes_),
        dist_(nodes_.size(), kInf),
        key_(nodes_.size(), kInf),
        aim_distance_(nodes_.size(), -1.0),
        parent_(nodes_.size(), -1),
        settled_(nodes_.size(), 0),
        heap_(nodes_.size()),
        reflex_grid_(nodes_, r_) {}

  // From `source`: before a node is settled, stop(its key) true ends the
  // search; after a path end u is settled, settled_end(u, its distance)
  // false ends it. True when nothing was left to search. Distances and
  // paths of the settled nodes hold until the next run.
  //
  // improved_end(u, d), called when a path end's tentative distance falls
  // to d, returns a bound on what is left worth searching: an edge to a
  // node v is not tested when d(v) + the lower bound at v exceeds it. It
  // must bound the key of every node on a path still wanted (a tentative
  // distance of the farthest path end wanted: a tentative distance is at
  // least the true one), and +inf until it can. On open ground most of a
  // search's segment tests go to nodes the wanted paths never pass.
  template <class Stop, class SettledEnd, class ImprovedEnd>
  bool run(std::uint32_t source, const std::vector<Point>& aims, Stop stop, SettledEnd settled_end,
           ImprovedEnd improved_end, double initial_bound = kInf) {
    for (const auto v : touched_) {
      dist_[v] = key_[v] = kInf;
      parent_[v] = -1;
      settled_[v] = 0;
    }
    for (const auto v : aimed_) aim_distance_[v] = -1.0;
    touched_.clear();
    aimed_.clear();
    settled_count_ = 0;
    aims_ = &aims;
    double bound = initial_bound;
    dist_[source] = 0.0;
    key_[source] = lower_bound_left(source);
    touched_.push_back(source);
    heap_.push_or_decrease(source, key_);
    const auto total = static_cast<std::uint32_t>(nodes_.size());
    while (!heap_.empty()) {
      const std::uint32_t u = heap_.pop(key_);
      if (stop(key_[u])) return give_up();
      settled_[u] = 1;
      settled_count_ += u < r_;
      if (u >= r_ && u != source) {
        if (!settled_end(u, dist_[u])) return give_up();
        continue;
      }
      const double d = dist_[u];
      auto relax = [&](std::uint32_t v) {
        if (settled_[v] || v == u) return;
        const double ux = nodes_[v].x() - nodes_[u].x(), uy = nodes_[v].y() - nodes_[u].y();
        const double candidate = d + std::sqrt(ux * ux + uy * uy);
        if (!(candidate < dist_[v])) return;
        // (The slack: the bound and the key sum the same lengths in other orders.)
        if (bound < kInf && candidate + lower_bound_left(v) > bound + 1e-9) return;
        if (u < r_ && corners_.drops(u, ux, uy)) return;
        if (v < r_ && corners_.drops(v, -ux, -uy)) return;
        if (!nodes_see_each_other(cspace_, nodes_[u], nodes_[v])) return;
        if (dist_[v] == kInf) touched_.push_back(v);
        dist_[v] = candidate;
        key_[v] = candidate + lower_bound_left(v);
        parent_[v] = static_cast<std::int32_t>(u);
        heap_.push_or_decrease(v, key_);
        if (v >= r_) bound = improved_end(v, candidate);
      };
      // The order of the relaxations from one node changes no distance
      // (each improves one node's), so the path ends come first: they may
      // set the bound. With a bound, only reflex nodes within bound - d of
      // u can be worth an edge, and the grid lists them.
      for (std::uint32_t v = r_; v < total; ++v) relax(v);
      if (bound < kInf) {
        reflex_grid_.for_each_within(nodes_[u], bound - d + 1e-9, relax);
      } else if (u < r_) {
        // Every reflex node: the corners' test first, for a block at once
        // (both ends, vectorised, no square root), as pruned_graph_edges
        // does; relax() repeats it for those it keeps, so the edges tested
        // are the same. Most of a settled node's pairs end here.
        constexpr std::uint32_t kBlock = 256;
        double score[kBlock];
        for (std::uint32_t first = 0; first < r_; first += kBlock) {
          const std::uint32_t count = std::min(kBlock, r_ - first);
          corners_.scores(u, first, count, score);
          for (std::uint32_t t = 0; t < count; ++t)
            if (!(score[t] < 0.0)) relax(first + t);
        }
      } else {
        for (std::uint32_t v = 0; v < r_; ++v) relax(v);
      }
    }
    return true;
  }
  template <class Stop, class SettledEnd>
  bool run(std::uint32_t source, const std::vector<Point>& aims, Stop stop, SettledEnd settled_end) {
    return run(source, aims, stop, settled_end, [](std::uint32_t, double) { return kInf; });
  }

  // Reflex nodes settled by the last run.
  std::size_t settled_count() const { return settled_count_; }

  // The path from the last run's source to settled node v, source first.
  std::vector<Point> path_to(std::uint32_t v) const {
    std::vector<Point> path;
    for (auto w = static_cast<std::int32_t>(v); w >= 0; w = parent_[static_cast<std::size_t>(w)])
      path.push_back(nodes_[static_cast<std::size_t>(w)]);
    std::reverse(path.begin(), path.end());
    return path;
  }

 private:
  bool give_up() {
    while (!heap_.empty()) heap_.pop(key_);
    return false;
  }

  double lower_bound_left(std::uint32_t v) {
    if (aim_distance_[v] < 0.0) {
      aimed_.push_back(v);
      double least = aims_->empty() ? 0.0 : kInf;
      for (const Point& a : *aims_) least = std::min(least, distance(nodes_[v], a));
      aim_distance_[v] = least;
    }
    return aim_distance_[v];
  }

  const ConfigurationSpace& cspace_;
  const std::vector<Point> nodes_;
  const std::uint32_t r_;
  const Corners corners_;
  std::vector<double> dist_, key_, aim_distance_;
  std::vector<std::int32_t> parent_;
  std::vector<char> settled_;
  std::vector<std::uint32_t> touched_, aimed_;  // what the next run resets
  NodeHeap heap_;
  NodeGrid reflex_grid_;  // nodes 0..r-1
  const std::vector<Point>* aims_ = nullptr;
  std::size_t settled_count_ = 0;
};

}  // namespace

PathMatrix shortest_path_matrix(const ConfigurationSpace& cspace, const Point& start,
                                const std::vector<Point>& targets, const PathMatrixOptions& options,
                                VisibilityCache* cache) {
  const std::int64_t tests_before = cspace.segment_tests();
  const auto r = static_cast<std::uint32_t>(cspace.reflex_nodes().size());
  const std::size_t n = targets.size();
  const std::vector<Point> nodes = graph_nodes(cspace, start, targets);
  const std::uint32_t first_point = r;
  const auto total = static_cast<std::uint32_t>(nodes.size());

  // 1. The graph (pruned_graph_edges).
  EdgeList edges = pruned_graph_edges(cspace, nodes, r, options.tangent_pruning, cache);
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
  // The points between_m holds rows for: every target, or (once the start's
  // row is known) the nearest only.
  std::vector<char> in_rows(total, 1);
  const std::uint32_t sources_end = options.between_targets ? total - 1 : std::min(total - 1, first_point + 1);
  for (std::uint32_t p = first_point; p < sources_end; ++p) {
    if (!in_rows[p]) continue;
    std::uint32_t wanted_count = 0;
    for (std::uint32_t q = first_point; q < total; ++q) {
      straight[q] = q > p && in_rows[q] && cspace.segment_free(nodes[p], nodes[q]);
      wanted[q] = q > p && in_rows[q] && !straight[q];
      wanted_count += wanted[q];
    }
    if (wanted_count > 0) dijkstra(graph, p, first_point, wanted, wanted_count, dist, parent, settled, touched, heap);
    for (std::uint32_t q = p + 1; q < total; ++q) {
      if (!in_rows[q]) continue;
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
    if (p == first_point && options.between_nearest > 0) {
      out.nearest = nearest_by_length(out.from_start_m, options.between_choice, options.between_nearest);
      std::fill(in_rows.begin() + first_point + 1, in_rows.end(), 0);
      for (const int t : out.nearest) in_rows[first_point + 1 + static_cast<std::uint32_t>(t)] = 1;
    }
  }

  out.reflex_nodes = r;
  out.graph_edges = static_cast<std::int64_t>(edges.a.size());
  out.segment_tests = cspace.segment_tests() - tests_before;
  return out;
}

namespace {

// A lazy search from the start that settles more reflex nodes than this is
// on its way to testing as many pairs as the whole pruned graph, one by one
// where the graph scores them in blocks and a VisibilityCache keeps most of
// them from the last plan (a ragged map: thousands of reflex nodes along
// walls a scan at a time drew): it gives up for the whole graph's row.
std::size_t lazy_settle_budget(std::uint32_t reflex_nodes) { return reflex_nodes / 10 + 64; }

}  // namespace

PathMatrix shortest_paths_to_cheapest(const ConfigurationSpace& cspace, const Point& start,
                                      const std::vector<Point>& targets, const CheapestTargetQuery& query,
                                      VisibilityCache* cache) {
  const std::int64_t tests_before = cspace.segment_tests();
  const auto r = static_cast<std::uint32_t>(cspace.reflex_nodes().size());
  const std::size_t n = targets.size();
  LazySearch search(cspace, graph_nodes(cspace, start, targets), r);
  const std::uint32_t source = r;

  PathMatrix out;
  out.from_start_m.assign(n, kInf);
  out.path_from_start.resize(n);
  out.reflex_nodes = r;
  const WantedTargets wanted = count_wanted(n, query.choice, query.required);
  std::size_t required_left = wanted.required;
  if (required_left == 0 && wanted.choices == 0) {  // nothing wanted: nothing searched
    out.all_searched = false;
    out.segment_tests = 0;
    return out;
  }
  double best_cost = kInf;
  const std::size_t settle_budget = lazy_settle_budget(r);
  bool over_budget = false;
  // A far goal is searched along the way to it, not in a disc around the robot.
  out.all_searched = search.run(
      source, search_aims(targets, query.choice, query.required),
      // Every path to a target through what is left costs at least `key`.
      [&](double key) {
        return (required_left == 0 && key > best_cost) || (over_budget = search.settled_count() > settle_budget);
      },
      [&](std::uint32_t u, double d) {
        const std::size_t t = u - source - 1;
        out.path_from_start[t] = search.path_to(u);
        out.from_start_m[t] = d;
        required_left -= is_required(query.required, t);
        best_cost = std::min(best_cost, query.cost(t, d, out.path_from_start[t]));
        return true;
      });
  if (over_budget) {
    PathMatrixOptions whole;
    whole.between_targets = false;
    out = shortest_path_matrix(cspace, start, targets, whole, cache);
  }
  out.segment_tests = cspace.segment_tests() - tests_before;
  return out;
}

namespace {

// shortest_paths_among_nearest's steps. The targets are nodes r + 1 + t of
// the search's graph (graph_nodes), the start node r.
struct NearestTargetsSearch {
  const ConfigurationSpace& cspace;
  const Point& start;
  const std::vector<Point>& targets;
  const NearestTargetsQuery& query;
  LazySearch& search;
  std::uint32_t r;
  VisibilityCache* cache;

  std::size_t n() const { return targets.size(); }
  bool is_choice(std::size_t t) const { return planning::is_choice(query.choice, t); }
  bool is_required(std::size_t t) const { return planning::is_required(query.required, t); }

  // 1. From the start until `count` choice targets and every required one
  // are settled: targets are settled in the order of their lengths (their
  // lower bound is 0), so the first `count` choice targets settled are the
  // nearest. False when the search gave up (see below).
  bool search_from_start(PathMatrix& out) const {
    const WantedTargets wanted = count_wanted(n(), query.choice, query.required);
    std::size_t required_left = wanted.required;
    const std::vector<Point> aims = search_aims(targets, query.choice, query.required);
    const std::size_t need = std::min(query.count, wanted.choices);
    if (need == 0 && required_left == 0) {  // nothing wanted: nothing searched
      out.all_searched = false;
      return true;
    }
    // What is worth searching: up to the need-th least tentative length of
    // a choice target, and the greatest of a required one.
    std::vector<double> tentative(n(), kInf), least;
    auto bound_after = [&](std::uint32_t u, double d) {
      tentative[u - r - 1] = d;
      least.clear();
      double bound = 0.0;
      for (std::size_t t = 0; t < n(); ++t) {
        if (is_required(t)) bound = std::max(bound, tentative[t]);
        if (is_choice(t) && tentative[t] < kInf) least.push_back(tentative[t]);
      }
      if (need == 0) return bound;  // the required only
      if (least.size() < need) return kInf;
      std::nth_element(least.begin(), least.begin() + static_cast<std::ptrdiff_t>(need - 1), least.end());
      return std::max(bound, least[need - 1]);
    };
    // Past the budget it gives up for the whole matrix.
    const std::size_t settle_budget = lazy_settle_budget(r);
    bool over_budget = false;
    out.all_searched = search.run(
        r, aims, [&](double) { return over_budget = search.settled_count() > settle_budget; },
        [&](std::uint32_t u, double d) {
          const std::size_t t = u - r - 1;
          out.path_from_start[t] = search.path_to(u);
          out.from_start_m[t] = d;
          required_left -= is_required(t);
          if (is_choice(t) && out.nearest.size() < query.count) out.nearest.push_back(static_cast<int>(t));
          return required_left > 0 || out.nearest.size() < query.count;
        },
        bound_after);
    return !over_budget;
  }

  // The whole graph, with the start's row and the lengths between the
  // `count` nearest choice targets only.
  PathMatrix whole_matrix() const {
    PathMatrixOptions options;
    options.between_targets = query.count > 0;
    options.between_nearest = query.count;
    options.between_choice = query.choice;
    PathMatrix whole = shortest_path_matrix(cspace, start, targets, options, cache);
    if (!options.between_targets) {  // none nearest: none between, as the contract says
      whole.between_m.assign(n() * n(), kInf);
      for (std::size_t i = 0; i < n(); ++i) whole.between_m[i * n() + i] = 0.0;
    }
    return whole;
  }

  // 2a. Between the nearest over the pruned graph of the reflex nodes and
  // those targets only.
  void between_over_the_graph(PathMatrix& out) const {
    std::vector<Point> nearest_points;
    for (const int t : out.nearest) nearest_points.push_back(targets[static_cast<std::size_t>(t)]);
    const PathMatrix among = shortest_path_matrix(cspace, start, nearest_points, {}, cache);
    for (std::size_t a = 0; a < out.nearest.size(); ++a)
      for (std::size_t b = 0; b < out.nearest.size(); ++b)
        out.between_m[static_cast<std::size_t>(out.nearest[a]) * n() + static_cast<std::size_t>(out.nearest[b])] =
            among.between(a, b);
  }

  // 2b. Between nearest target a and the later ones: the straight segment
  // where it is free, else one lazy search for those it does not see.
  void between_from(std::size_t a, PathMatrix& out) const {
    const auto ta = static_cast<std::size_t>(out.nearest[a]);
    const Point& pa = targets[ta];
    std::vector<Point> unseen;
    std::vector<char> wanted(n(), 0);
    for (std::size_t b = a + 1; b < out.nearest.size(); ++b) {
      const auto tb = static_cast<std::size_t>(out.nearest[b]);
      if (cspace.segment_free(pa, targets[tb])) {
        out.between_m[ta * n() + tb] = out.between_m[tb * n() + ta] = distance(pa, targets[tb]);
      } else {
        wanted[tb] = 1;
        unseen.push_back(targets[tb]);
      }
    }
    if (unseen.empty()) return;
    // Back along the path from the start to where the two paths part, and
    // on along the other: an upper bound on every length wanted, from the outset.
    double via_start = 0.0;
    for (std::size_t t = 0; t < n(); ++t)
      if (wanted[t])
        via_start = std::max(via_start, out.from_start_m[ta] + out.from_start_m[t] -
                                            2.0 * shared_length(out.path_from_start[ta], out.path_from_start[t]));
    std::size_t left = unseen.size();
    std::vector<double> tentative(n(), kInf);
    search.run(
        r + 1 + static_cast<std::uint32_t>(ta), unseen, [](double) { return false; },
        [&](std::uint32_t u, double d) {
          if (u == r) return true;  // the start: a path end here, not wanted
          const std::size_t t = u - r - 1;
          if (!wanted[t]) return true;
          out.between_m[ta * n() + t] = out.between_m[t * n() + ta] = d;
          return --left > 0;
        },
        [&](std::uint32_t u, double d) {  // worth searching: up to the farthest wanted
          if (u != r) tentative[u - r - 1] = d;
          double bound = 0.0;
          for (std::size_t t = 0; t < n(); ++t)
            if (wanted[t]) bound = std::max(bound, tentative[t]);
          return std::min(bound, via_start);
        },
        via_start);
  }
};

}  // namespace

PathMatrix shortest_paths_among_nearest(const ConfigurationSpace& cspace, const Point& start,
                                        const std::vector<Point>& targets, const NearestTargetsQuery& query,
                                        VisibilityCache* cache) {
  const std::int64_t tests_before = cspace.segment_tests();
  const auto r = static_cast<std::uint32_t>(cspace.reflex_nodes().size());
  const std::size_t n = targets.size();
  LazySearch search(cspace, graph_nodes(cspace, start, targets), r);
  const NearestTargetsSearch steps{cspace, start, targets, query, search, r, cache};

  PathMatrix out;
  out.from_start_m.assign(n, kInf);
  out.path_from_start.resize(n);
  out.between_m.assign(n * n, kInf);
  for (std::size_t i = 0; i < n; ++i) out.between_m[i * n + i] = 0.0;
  out.reflex_nodes = r;
  if (!steps.search_from_start(out)) {
    out = steps.whole_matrix();
  } else if (search.settled_count() * out.nearest.size() > r) {
    // A search from each of the nearest would test more pairs of nodes than
    // the pruned graph has (the start's search had to settle much of the
    // map: a ragged one, or the nearest far apart).
    steps.between_over_the_graph(out);
  } else {
    for (std::size_t a = 0; a < out.nearest.size(); ++a) steps.between_from(a, out);
  }
  out.segment_tests = cspace.segment_tests() - tests_before;
  return out;
}

}  // namespace pex::planning
