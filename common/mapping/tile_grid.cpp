#include "mapping/tile_grid.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pex::mapping {

namespace {

// A crossing within this of a grid line is put on it, and one within this of
// an end point or of the previous crossing is dropped.
constexpr double kGridSnap = 1e-9;

// Points where segment p-q crosses grid lines, ordered from p to q.
void grid_crossings(const Point& p, const Point& q, const TileGrid& grid, std::vector<Point>& out) {
  out.clear();
  // Canonical order, so both traversal directions compute the same bits.
  const bool swap = (q.x() < p.x()) || (q.x() == p.x() && q.y() < p.y());
  const Point a = swap ? q : p, b = swap ? p : q;
  std::vector<std::pair<double, Point>> hits;
  auto snap = [&](double v) {
    const double g = grid.line(static_cast<std::int64_t>(std::round((v - grid.origin_m) / grid.size_m)));
    return std::abs(v - g) <= kGridSnap ? g : v;
  };
  if (a.x() != b.x()) {
    for (std::int64_t k = grid.index(a.x()); grid.line(k) < b.x(); ++k) {
      const double x = grid.line(k);
      if (x <= a.x()) continue;
      const double t = (x - a.x()) / (b.x() - a.x());
      hits.push_back({t, Point(x, snap(a.y() + t * (b.y() - a.y())))});
    }
  }
  const double ylo = std::min(a.y(), b.y()), yhi = std::max(a.y(), b.y());
  if (ylo != yhi) {
    for (std::int64_t k = grid.index(ylo); grid.line(k) < yhi; ++k) {
      const double y = grid.line(k);
      if (y <= ylo) continue;
      const double t = (y - a.y()) / (b.y() - a.y());
      hits.push_back({t, Point(snap(a.x() + t * (b.x() - a.x())), y)});
    }
  }
  std::sort(hits.begin(), hits.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  for (const auto& h : hits) {
    if (!out.empty() && bg::distance(out.back(), h.second) < kGridSnap) continue;
    if (bg::distance(h.second, a) < kGridSnap || bg::distance(h.second, b) < kGridSnap) continue;
    out.push_back(h.second);
  }
  if (swap) std::reverse(out.begin(), out.end());
}

// Splits ring's edges at grid lines; `types`, if given, is split alongside
// (each piece keeps its edge's type).
void split_ring(Ring& ring, std::vector<EdgeType>* types, const TileGrid& grid) {
  if (ring.size() < 2) return;
  Ring out;
  out.reserve(ring.size());
  std::vector<EdgeType> out_types;
  if (types) out_types.reserve(types->size());
  std::vector<Point> crossings;
  for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
    out.push_back(ring[i]);
    grid_crossings(ring[i], ring[i + 1], grid, crossings);
    out.insert(out.end(), crossings.begin(), crossings.end());
    if (types) out_types.insert(out_types.end(), 1 + crossings.size(), (*types)[i]);
  }
  out.push_back(ring.back());
  ring = std::move(out);
  if (types) *types = std::move(out_types);
}

}  // namespace

std::int32_t TileGrid::index(double v) const {
  // The k with line(k) <= v < line(k + 1): the plain quotient, put right
  // where line()'s rounding onto the overlay's grid moved the line across v.
  auto k = static_cast<std::int64_t>(std::floor((v - origin_m) / size_m));
  if (line(k) > v) --k;
  else if (line(k + 1) <= v) ++k;
  return static_cast<std::int32_t>(k);
}

Box TileGrid::box(const TileKey& key) const {
  return Box(Point(line(key.first), line(key.second)), Point(line(key.first + 1), line(key.second + 1)));
}

std::pair<TileKey, TileKey> TileGrid::range(const Box& envelope) const {
  return {{index(envelope.min_corner().x()), index(envelope.min_corner().y())},
          {index(envelope.max_corner().x()), index(envelope.max_corner().y())}};
}

void split_at_grid(MultiPolygon& geometry, double cell_m, double origin_m) {
  const TileGrid grid{cell_m, origin_m};
  for (auto& polygon : geometry) {
    split_ring(polygon.outer(), nullptr, grid);
    for (auto& inner : polygon.inners()) split_ring(inner, nullptr, grid);
  }
}

void split_at_grid(TypedPolygon& polygon, double cell_m, double origin_m) {
  const TileGrid grid{cell_m, origin_m};
  split_ring(polygon.geometry.outer(), &polygon.edge_types[0], grid);
  for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
    split_ring(polygon.geometry.inners()[k], &polygon.edge_types[1 + k], grid);
}

}  // namespace pex::mapping
