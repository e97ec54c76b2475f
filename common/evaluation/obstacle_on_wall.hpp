#pragma once
// How much of a map's obstacle-typed boundary lies on a real wall of the
// world: the share of obstacle edge length within a tolerance of a wall.
// Exact (no sampling): the part of an edge within `tolerance_m` of one wall
// segment is one parameter interval (the wall's tolerance capsule is convex),
// computed in closed form; the intervals of the walls near the edge (an
// R-tree over the walls) are merged and their lengths summed.
//
// Header-only: tests/mapping_accuracy links pex_sim and pex_mapping, not
// pex_evaluation, and uses this too.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <boost/geometry/index/rtree.hpp>

#include "mapping/typed_polygon.hpp"
#include "sim/sim.hpp"

namespace pex::evaluation {

// An R-tree over a world's wall segments.
class WallIndex {
 public:
  explicit WallIndex(const std::vector<sim::Wall>& walls) : walls_(walls) {
    std::vector<Entry> entries;
    entries.reserve(walls_.size());
    for (std::size_t i = 0; i < walls_.size(); ++i) {
      const auto& w = walls_[i];
      entries.emplace_back(mapping::Box(mapping::Point(std::min(w.x0, w.x1), std::min(w.y0, w.y1)),
                                        mapping::Point(std::max(w.x0, w.x1), std::max(w.y0, w.y1))),
                           i);
    }
    tree_ = Tree(entries.begin(), entries.end());  // packed (bulk loading)
  }

  // Distance (m) from p to the nearest wall; infinity without walls.
  double distance(const mapping::Point& p) const {
    double best = std::numeric_limits<double>::infinity();
    // The nearest boxes first; a wall's distance is at least its box's.
    for (auto it = tree_.qbegin(boost::geometry::index::nearest(p, static_cast<unsigned>(tree_.size())));
         it != tree_.qend(); ++it) {
      if (boost::geometry::distance(p, it->first) > best) break;
      best = std::min(best, boost::geometry::distance(p, segment(it->second)));
    }
    return best;
  }

  // Length (m) of segment a-b lying within tolerance_m of some wall.
  double length_near_walls(const mapping::Point& a, const mapping::Point& b, double tolerance_m) const {
    const double length = std::hypot(b.x() - a.x(), b.y() - a.y());
    if (!(length > 0.0)) return 0.0;
    const mapping::Box query(mapping::Point(std::min(a.x(), b.x()) - tolerance_m, std::min(a.y(), b.y()) - tolerance_m),
                             mapping::Point(std::max(a.x(), b.x()) + tolerance_m, std::max(a.y(), b.y()) + tolerance_m));
    std::vector<std::pair<double, double>> intervals;
    for (auto it = tree_.qbegin(boost::geometry::index::intersects(query)); it != tree_.qend(); ++it) {
      const auto& w = walls_[it->second];
      const auto interval = near_interval(a, b, w, tolerance_m);
      if (interval.first < interval.second) intervals.push_back(interval);
    }
    std::sort(intervals.begin(), intervals.end());
    double covered = 0.0, lo = 0.0, hi = -1.0;
    for (const auto& [s, e] : intervals) {
      if (s > hi) {
        if (hi > lo) covered += hi - lo;
        lo = s, hi = e;
      } else {
        hi = std::max(hi, e);
      }
    }
    if (hi > lo) covered += hi - lo;
    return covered * length;
  }

  // The parameters t in [0, 1] of a + t (b - a) within tol of wall w: one
  // interval (empty: first >= second). The capsule around w is convex, so
  // its intersection with the line is the hull of the intersections with
  // its rectangle and its two end discs.
  static std::pair<double, double> near_interval(const mapping::Point& a, const mapping::Point& b,
                                                 const sim::Wall& w, double tol) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    auto add = [&](double s, double e) {
      s = std::max(s, 0.0), e = std::min(e, 1.0);
      if (s <= e) lo = std::min(lo, s), hi = std::max(hi, e);
    };
    const double dx = b.x() - a.x(), dy = b.y() - a.y();
    // Discs at the wall's ends: |a + t d - c|^2 <= tol^2.
    for (const auto& [cx, cy] : {std::pair{w.x0, w.y0}, std::pair{w.x1, w.y1}}) {
      const double fx = a.x() - cx, fy = a.y() - cy;
      const double qa = dx * dx + dy * dy, qb = 2 * (fx * dx + fy * dy), qc = fx * fx + fy * fy - tol * tol;
      const double disc = qb * qb - 4 * qa * qc;
      if (qa > 0 && disc >= 0) {
        const double root = std::sqrt(disc);
        add((-qb - root) / (2 * qa), (-qb + root) / (2 * qa));
      }
    }
    // Rectangle: 0 <= u <= L along the wall, |v| <= tol across it.
    const double wx = w.x1 - w.x0, wy = w.y1 - w.y0, wl = std::hypot(wx, wy);
    if (wl > 0) {
      const double ux = wx / wl, uy = wy / wl;
      const double u0 = (a.x() - w.x0) * ux + (a.y() - w.y0) * uy, du = dx * ux + dy * uy;
      const double v0 = -(a.x() - w.x0) * uy + (a.y() - w.y0) * ux, dv = -dx * uy + dy * ux;
      double s = 0.0, e = 1.0;
      // Liang-Barsky: lo_bound <= value0 + t * slope <= hi_bound.
      auto clip = [&](double value0, double slope, double lo_bound, double hi_bound) {
        if (slope == 0.0) {
          if (value0 < lo_bound || value0 > hi_bound) s = 1.0, e = 0.0;
          return;
        }
        double t0 = (lo_bound - value0) / slope, t1 = (hi_bound - value0) / slope;
        if (t0 > t1) std::swap(t0, t1);
        s = std::max(s, t0), e = std::min(e, t1);
      };
      clip(u0, du, 0.0, wl);
      clip(v0, dv, -tol, tol);
      if (s <= e) add(s, e);
    }
    return {lo, hi};
  }

  const std::vector<sim::Wall>& walls() const { return walls_; }

 private:
  using Entry = std::pair<mapping::Box, std::size_t>;
  using Tree = boost::geometry::index::rtree<Entry, boost::geometry::index::rstar<16>>;
  mapping::Segment segment(std::size_t i) const {
    const auto& w = walls_[i];
    return {mapping::Point(w.x0, w.y0), mapping::Point(w.x1, w.y1)};
  }
  std::vector<sim::Wall> walls_;
  Tree tree_;
};

// Share (0..1) of the obstacle-typed edge length of `map` (in the world
// frame) within tolerance_m of a wall of the world. NaN when the map has no
// obstacle edges (nothing to judge).
inline double obstacle_on_wall(const mapping::TypedMultiPolygon& map, const WallIndex& walls, double tolerance_m) {
  double total = 0.0, on_wall = 0.0;
  mapping::for_each_edge(map, [&](const mapping::Point& a, const mapping::Point& b, mapping::EdgeType t) {
    if (t != mapping::EdgeType::kObstacle) return;
    total += std::hypot(b.x() - a.x(), b.y() - a.y());
    on_wall += walls.length_near_walls(a, b, tolerance_m);
  });
  return total > 0 ? on_wall / total : std::numeric_limits<double>::quiet_NaN();
}

inline double obstacle_on_wall(const mapping::TypedMultiPolygon& map, const sim::World& world, double tolerance_m) {
  return obstacle_on_wall(map, WallIndex(world.walls), tolerance_m);
}

}  // namespace pex::evaluation
