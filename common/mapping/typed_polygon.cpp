#include "mapping/typed_polygon.hpp"

#include <cmath>
#include <utility>

namespace pex::mapping {

const char* to_string(EdgeType type) {
  switch (type) {
    case EdgeType::kObstacle: return "obstacle";
    case EdgeType::kFrontier: return "frontier";
    case EdgeType::kBorder: return "border";
  }
  return "?";
}

namespace {
bool ring_types_match(const Ring& ring, const std::vector<EdgeType>& types) {
  return ring.size() >= 1 && types.size() + 1 == ring.size();
}
}  // namespace

bool types_match_rings(const TypedPolygon& polygon) {
  if (polygon.edge_types.size() != 1 + polygon.geometry.inners().size()) return false;
  if (!ring_types_match(polygon.geometry.outer(), polygon.edge_types[0])) return false;
  for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
    if (!ring_types_match(polygon.geometry.inners()[k], polygon.edge_types[1 + k])) return false;
  return true;
}

bool types_match_rings(const TypedMultiPolygon& polygons) {
  for (const auto& p : polygons)
    if (!types_match_rings(p)) return false;
  return true;
}

bool is_valid(const TypedPolygon& polygon, std::string* why) {
  if (!types_match_rings(polygon)) {
    if (why) *why = "edge types do not match the rings";
    return false;
  }
  std::string message;
  if (!bg::is_valid(polygon.geometry, message)) {
    if (why) *why = message;
    return false;
  }
  return true;
}

bool is_valid(const TypedMultiPolygon& polygons, std::string* why) {
  if (!types_match_rings(polygons)) {
    if (why) *why = "edge types do not match the rings";
    return false;
  }
  // The polygons of a map must also be interior-disjoint: check them as one
  // Boost multi-polygon.
  const MultiPolygon geometry = geometry_of(polygons);
  std::string message;
  if (!bg::is_valid(geometry, message)) {
    if (why) *why = message;
    return false;
  }
  return true;
}

std::size_t vertex_count(const Polygon& polygon) {
  auto ring_count = [](const Ring& r) { return r.empty() ? 0 : r.size() - 1; };
  std::size_t n = ring_count(polygon.outer());
  for (const auto& inner : polygon.inners()) n += ring_count(inner);
  return n;
}

std::size_t vertex_count(const MultiPolygon& polygons) {
  std::size_t n = 0;
  for (const auto& p : polygons) n += vertex_count(p);
  return n;
}

std::size_t vertex_count(const TypedMultiPolygon& polygons) {
  std::size_t n = 0;
  for (const auto& p : polygons) n += vertex_count(p.geometry);
  return n;
}

double area(const TypedMultiPolygon& polygons) {
  double a = 0.0;
  for (const auto& p : polygons) a += bg::area(p.geometry);
  return a;
}

double edge_length(const TypedMultiPolygon& polygons, EdgeType type) {
  double length = 0.0;
  for_each_edge(polygons, [&](const Point& a, const Point& b, EdgeType t) {
    if (t == type) length += bg::distance(a, b);
  });
  return length;
}

MultiPolygon geometry_of(const TypedMultiPolygon& polygons) {
  MultiPolygon out;
  out.reserve(polygons.size());
  for (const auto& p : polygons) out.push_back(p.geometry);
  return out;
}

TypedMultiPolygon with_uniform_type(const MultiPolygon& polygons, EdgeType type) {
  TypedMultiPolygon out;
  out.reserve(polygons.size());
  for (const auto& geometry : polygons) {
    TypedPolygon p{geometry, {}};
    p.edge_types.emplace_back(geometry.outer().empty() ? 0 : geometry.outer().size() - 1, type);
    for (const auto& inner : geometry.inners())
      p.edge_types.emplace_back(inner.empty() ? 0 : inner.size() - 1, type);
    out.push_back(std::move(p));
  }
  return out;
}

std::size_t memory_bytes(const TypedMultiPolygon& polygons) {
  std::size_t bytes = polygons.capacity() * sizeof(TypedPolygon);
  for (const auto& p : polygons) {
    bytes += p.geometry.outer().capacity() * sizeof(Point);
    bytes += p.geometry.inners().capacity() * sizeof(Ring);
    for (const auto& inner : p.geometry.inners()) bytes += inner.capacity() * sizeof(Point);
    bytes += p.edge_types.capacity() * sizeof(std::vector<EdgeType>);
    for (const auto& t : p.edge_types) bytes += t.capacity() * sizeof(EdgeType);
  }
  return bytes;
}

namespace {

double distance_to_line(const Point& p, const Point& a, const Point& b) {
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  const double length = std::hypot(dx, dy);
  if (length <= 0.0) return std::hypot(p.x() - a.x(), p.y() - a.y());
  return std::abs(dx * (p.y() - a.y()) - dy * (p.x() - a.x())) / length;
}

// Simplifies one closed ring given as n distinct vertices with n edge types.
// Returns false if the ring would collapse below 3 vertices.
bool simplify_ring(const Ring& ring, const std::vector<EdgeType>& types, double epsilon_m,
                   Ring& out_ring, std::vector<EdgeType>& out_types) {
  const std::size_t n = ring.size() - 1;
  if (n < 4) return false;
  // Work on an unrolled copy starting at a type change (or at 0 for a uniform
  // ring), so every run is a contiguous range.
  std::size_t start = 0;
  bool uniform = true;
  for (std::size_t i = 0; i < n; ++i) {
    if (types[(i + n - 1) % n] != types[i]) {
      start = i;
      uniform = false;
      break;
    }
  }
  std::vector<Point> points(n + 1);
  std::vector<EdgeType> t(n);
  for (std::size_t i = 0; i < n; ++i) {
    points[i] = ring[(start + i) % n];
    t[i] = types[(start + i) % n];
  }
  points[n] = points[0];
  std::vector<bool> keep(n + 1, false);
  keep[0] = keep[n] = true;
  if (uniform) {
    // Anchor the farthest vertex from vertex 0 so both halves are open chains.
    std::size_t far = 1;
    double best = -1.0;
    for (std::size_t i = 1; i < n; ++i) {
      const double d = bg::comparable_distance(points[0], points[i]);
      if (d > best) best = d, far = i;
    }
    keep[far] = true;
    rdp_keep(points, 0, far, epsilon_m, keep);
    rdp_keep(points, far, n, epsilon_m, keep);
  } else {
    std::size_t run_start = 0;
    for (std::size_t i = 1; i <= n; ++i) {
      if (i == n || t[i] != t[run_start]) {
        keep[i] = true;
        rdp_keep(points, run_start, i, epsilon_m, keep);
        run_start = i;
      }
    }
  }
  out_ring.clear();
  out_types.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    out_ring.push_back(points[i]);
    out_types.push_back(t[i]);  // a kept vertex starts an edge of its run's type
  }
  if (out_ring.size() < 3) return false;
  out_ring.push_back(out_ring.front());
  return true;
}

}  // namespace

void rdp_keep(const std::vector<Point>& points, std::size_t first, std::size_t last,
              double epsilon_m, std::vector<bool>& keep) {
  // Iterative (an explicit stack), since rings can have 100k vertices.
  std::vector<std::pair<std::size_t, std::size_t>> stack{{first, last}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (b <= a + 1) continue;
    double worst = -1.0;
    std::size_t worst_index = a;
    for (std::size_t i = a + 1; i < b; ++i) {
      const double d = distance_to_line(points[i], points[a], points[b]);
      if (d > worst) worst = d, worst_index = i;
    }
    if (worst > epsilon_m) {
      keep[worst_index] = true;
      stack.push_back({a, worst_index});
      stack.push_back({worst_index, b});
    }
  }
}

TypedMultiPolygon simplify_typed(const TypedMultiPolygon& polygons, double epsilon_m,
                                 bool check_each_polygon) {
  if (epsilon_m <= 0.0) return polygons;
  TypedMultiPolygon out;
  out.reserve(polygons.size());
  for (const auto& polygon : polygons) {
    TypedPolygon simplified;
    simplified.edge_types.resize(1 + polygon.geometry.inners().size());
    bool ok = simplify_ring(polygon.geometry.outer(), polygon.edge_types[0], epsilon_m,
                            simplified.geometry.outer(), simplified.edge_types[0]);
    for (std::size_t k = 0; ok && k < polygon.geometry.inners().size(); ++k) {
      Ring inner;
      std::vector<EdgeType> inner_types;
      if (simplify_ring(polygon.geometry.inners()[k], polygon.edge_types[1 + k], epsilon_m,
                        inner, inner_types)) {
        simplified.geometry.inners().push_back(std::move(inner));
        simplified.edge_types[1 + simplified.geometry.inners().size() - 1] =
            std::move(inner_types);
      } else {
        // Too small to simplify: keep the hole as it was.
        simplified.geometry.inners().push_back(polygon.geometry.inners()[k]);
        simplified.edge_types[simplified.geometry.inners().size()] = polygon.edge_types[1 + k];
      }
    }
    if (!ok) {
      // A small outer ring (< 4 vertices or collapsing) is kept as it was.
      out.push_back(polygon);
      continue;
    }
    if (!check_each_polygon || bg::is_valid(simplified.geometry)) {
      out.push_back(std::move(simplified));
    } else {
      out.push_back(polygon);
    }
  }
  return out;
}

}  // namespace pex::mapping
