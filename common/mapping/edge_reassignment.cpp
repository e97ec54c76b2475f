#include "mapping/edge_reassignment.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

namespace pex::mapping {

namespace bgi = boost::geometry::index;

double edge_match_penalty(const Point& out_a, const Point& out_b, const Point& in_a,
                          const Point& in_b) {
  const double dx = out_b.x() - out_a.x(), dy = out_b.y() - out_a.y();
  const double length = std::hypot(dx, dy);
  if (length <= 1e-15) return 2.0 * bg::distance(out_a, Segment(in_a, in_b));
  const double ux = dx / length, uy = dy / length;
  // Perpendicular distances of the input end points from the output line.
  auto perpendicular = [&](const Point& p) {
    return std::abs(ux * (p.y() - out_a.y()) - uy * (p.x() - out_a.x()));
  };
  // Positions of the input end points along the output edge (out_a at 0).
  auto along = [&](const Point& p) { return ux * (p.x() - out_a.x()) + uy * (p.y() - out_a.y()); };
  const double s1 = along(in_a), s2 = along(in_b);
  const double lo = std::min(s1, s2), hi = std::max(s1, s2);
  // How far the output edge's ends lie beyond the input edge's projection
  // (not clamped: a gap between the two counts too, as the paper's y
  // differences do). This makes P >= distance(input edge, output edge).
  const double d1 = std::max(lo, 0.0);
  const double d2 = std::max(length - hi, 0.0);
  return perpendicular(in_a) + perpendicular(in_b) + d1 + d2;
}

void EdgeTypeIndex::add_edge(const Point& a, const Point& b, EdgeType type) {
  edges_.push_back({a, b, type});
  tree_.reset();
}

void EdgeTypeIndex::add(const TypedPolygon& polygon) {
  for_each_edge(polygon, [&](const Point& a, const Point& b, EdgeType t) { add_edge(a, b, t); });
}

void EdgeTypeIndex::add(const TypedMultiPolygon& polygons) {
  for (const auto& p : polygons) add(p);
}

void EdgeTypeIndex::add_as(const TypedMultiPolygon& polygons, EdgeType type) {
  for_each_edge(polygons, [&](const Point& a, const Point& b, EdgeType) { add_edge(a, b, type); });
}

void EdgeTypeIndex::add_as(const MultiPolygon& polygons, EdgeType type) {
  auto add_ring = [&](const Ring& ring) {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) add_edge(ring[i], ring[i + 1], type);
  };
  for (const auto& p : polygons) {
    add_ring(p.outer());
    for (const auto& inner : p.inners()) add_ring(inner);
  }
}

void EdgeTypeIndex::build() {
  std::vector<Value> values;
  values.reserve(edges_.size());
  for (std::size_t i = 0; i < edges_.size(); ++i) {
    Box box;
    bg::envelope(Segment(edges_[i].a, edges_[i].b), box);
    values.emplace_back(box, static_cast<std::uint32_t>(i));
  }
  // The range constructor bulk-loads (packing), faster than inserting one by one.
  tree_ = std::make_unique<Tree>(values.begin(), values.end());
}

EdgeTypeIndex::Match EdgeTypeIndex::match(const Point& a, const Point& b,
                                          double search_radius_m) const {
  Match best;
  best.penalty = std::numeric_limits<double>::infinity();
  if (edges_.empty()) return best;
  auto consider = [&](std::uint32_t i) {
    const Edge& e = edges_[i];
    const double p = edge_match_penalty(a, b, e.a, e.b);
    ++best.candidates;
    if (best.edge < 0 || better_match(p, e.type, best.penalty, best.type)) {
      best.penalty = p;
      best.type = e.type;
      best.edge = i;
    }
    // Nothing beats a zero-penalty obstacle edge: stop.
    return !(best.type == EdgeType::kObstacle && best.penalty <= kPenaltyTieTolerance);
  };
  if (!tree_) {
    // Not built: a plain scan over every edge (same result, slower).
    for (std::uint32_t i = 0; i < edges_.size(); ++i)
      if (!consider(i)) return best;
    return best;
  }
  // Exact search: P >= distance(input edge, output edge), so once the best
  // penalty found is within the searched radius, no edge outside can beat it;
  // otherwise the radius grows to the best penalty and the query repeats.
  double r = std::max(search_radius_m, 0.0);
  const Point middle((a.x() + b.x()) / 2, (a.y() + b.y()) / 2);
  for (int round = 0;; ++round) {
    const Box query(Point(std::min(a.x(), b.x()) - r, std::min(a.y(), b.y()) - r),
                    Point(std::max(a.x(), b.x()) + r, std::max(a.y(), b.y()) + r));
    for (auto it = tree_->qbegin(bgi::intersects(query)); it != tree_->qend(); ++it)
      if (!consider(it->second)) return best;
    if (best.edge < 0) {
      // Nothing near: the nearest edge bounds the radius to search.
      for (auto it = tree_->qbegin(bgi::nearest(middle, 1)); it != tree_->qend(); ++it)
        consider(it->second);
    }
    if (best.penalty + 2 * kPenaltyTieTolerance <= r || round >= 8) return best;
    r = best.penalty + 4 * kPenaltyTieTolerance;
  }
}

}  // namespace pex::mapping
