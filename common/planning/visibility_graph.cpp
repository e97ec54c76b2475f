#include "planning/visibility_graph.hpp"

#include <algorithm>
#include <functional>
#include <queue>
#include <utility>

namespace pex::planning {

ShortestPaths shortest_paths(const ConfigurationSpace& cspace, const Point& start,
                             const std::vector<Point>& targets) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const auto& reflex = cspace.reflex_nodes();
  // Node 0: start; 1..R: reflex vertices; R+1..: targets.
  std::vector<Point> nodes;
  nodes.reserve(1 + reflex.size() + targets.size());
  nodes.push_back(start);
  nodes.insert(nodes.end(), reflex.begin(), reflex.end());
  const std::size_t first_target = nodes.size();
  nodes.insert(nodes.end(), targets.begin(), targets.end());
  const std::size_t n = nodes.size();

  std::vector<double> dist(n, kInf);
  std::vector<std::int64_t> parent(n, -1);
  std::vector<char> settled(n, 0);
  const std::int64_t tests_before = cspace.segment_tests();

  using Entry = std::pair<double, std::size_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  dist[0] = 0.0;
  queue.emplace(0.0, 0);
  std::size_t targets_left = targets.size();
  while (!queue.empty() && targets_left > 0) {
    const auto [d, u] = queue.top();
    queue.pop();
    if (settled[u] || d > dist[u]) continue;
    settled[u] = 1;
    if (u >= first_target) {
      --targets_left;
      continue;  // targets are path ends
    }
    for (std::size_t v = 1; v < n; ++v) {
      if (settled[v]) continue;
      const double candidate = d + distance(nodes[u], nodes[v]);
      // The cheap test first: only an improving edge is worth a segment test.
      if (!(candidate < dist[v])) continue;
      if (!cspace.segment_free(nodes[u], nodes[v])) continue;
      dist[v] = candidate;
      parent[v] = static_cast<std::int64_t>(u);
      queue.emplace(candidate, v);
    }
  }

  ShortestPaths out;
  out.nodes = static_cast<std::int64_t>(n);
  out.segment_tests = cspace.segment_tests() - tests_before;
  out.length_m.resize(targets.size(), kInf);
  out.path.resize(targets.size());
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const std::size_t node = first_target + t;
    if (!settled[node]) continue;
    out.length_m[t] = dist[node];
    std::vector<Point> path;
    for (std::int64_t v = static_cast<std::int64_t>(node); v >= 0; v = parent[static_cast<std::size_t>(v)])
      path.push_back(nodes[static_cast<std::size_t>(v)]);
    std::reverse(path.begin(), path.end());
    out.path[t] = std::move(path);
  }
  return out;
}

}  // namespace pex::planning
