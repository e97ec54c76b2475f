#pragma once
// Test and benchmark support (not used by the library): a tiny world of wall
// segments, a noise-free ray caster and random worlds, so the mapping tests
// and pex-bench-mapping need no simulator.
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "mapping/edge_reassignment.hpp"
#include "mapping/scan_polygon.hpp"

namespace pex::mapping::testing {

using geometry::Pose2;

struct Wall {
  Point a, b;
};

// Range along the ray from (x, y) at `angle` to the nearest wall, or +inf.
inline double cast_ray(const std::vector<Wall>& walls, double x, double y, double angle) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& w : walls) {
    const double ex = w.b.x() - w.a.x(), ey = w.b.y() - w.a.y();
    const double det = dx * (-ey) - dy * (-ex);
    if (std::abs(det) < 1e-12) continue;
    const double rx = w.a.x() - x, ry = w.a.y() - y;
    const double t = (rx * (-ey) - ry * (-ex)) / det;
    const double u = (dx * ry - dy * rx) / det;
    if (t > 0.0 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
  }
  return best;
}

struct ScanSpec {
  double angle_min = -3.0 * std::numbers::pi / 4.0;
  double angle_increment = std::numbers::pi / 360.0;  // 0.5 degree
  int beams = 541;
  double range_max_m = 10.0;
};

// Ranges seen from `pose`; beyond range_max the reading is +inf (no return).
// noise_m > 0 adds Gaussian range noise from `rng`.
inline std::vector<float> cast_scan(const std::vector<Wall>& walls, const Pose2& pose,
                                    const ScanSpec& spec, double noise_m = 0.0,
                                    std::mt19937_64* rng = nullptr) {
  // Only walls that can be within range matter (big worlds in the benchmark).
  std::vector<Wall> near;
  const double reach = spec.range_max_m + 1e-6;
  for (const auto& w : walls) {
    if (std::min(w.a.x(), w.b.x()) > pose.x_m + reach || std::max(w.a.x(), w.b.x()) < pose.x_m - reach ||
        std::min(w.a.y(), w.b.y()) > pose.y_m + reach || std::max(w.a.y(), w.b.y()) < pose.y_m - reach)
      continue;
    near.push_back(w);
  }
  std::vector<float> ranges(static_cast<std::size_t>(spec.beams));
  std::normal_distribution<double> noise(0.0, noise_m > 0 ? noise_m : 1.0);
  for (int i = 0; i < spec.beams; ++i) {
    double r = cast_ray(near, pose.x_m, pose.y_m, pose.theta_rad + spec.angle_min + spec.angle_increment * i);
    if (noise_m > 0 && rng && std::isfinite(r)) r += noise(*rng);
    ranges[static_cast<std::size_t>(i)] =
        r < spec.range_max_m ? static_cast<float>(r) : std::numeric_limits<float>::infinity();
  }
  return ranges;
}

inline void add_box(std::vector<Wall>& walls, double x0, double y0, double x1, double y1) {
  walls.push_back({Point(x0, y0), Point(x1, y0)});
  walls.push_back({Point(x1, y0), Point(x1, y1)});
  walls.push_back({Point(x1, y1), Point(x0, y1)});
  walls.push_back({Point(x0, y1), Point(x0, y0)});
}

// A room [0, w] x [0, h] with `pillars` random axis-aligned boxes inside.
inline std::vector<Wall> random_room(double w, double h, int pillars, std::mt19937_64& rng) {
  std::vector<Wall> walls;
  add_box(walls, 0, 0, w, h);
  std::uniform_real_distribution<double> ux(1.0, w - 2.0), uy(1.0, h - 2.0), us(0.2, 1.0);
  for (int k = 0; k < pillars; ++k) {
    const double x = ux(rng), y = uy(rng);
    add_box(walls, x, y, x + us(rng), y + us(rng));
  }
  return walls;
}

// A lattice of small rotated hexagonal "rocks" `spacing_m` apart over
// [0, w] x [0, h], inside a boundary box: many holes, many vertices.
inline std::vector<Wall> rock_field(double w, double h, double spacing_m, std::mt19937_64& rng) {
  std::vector<Wall> walls;
  add_box(walls, 0, 0, w, h);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2), radius(0.15, 0.35), phase(0.0, 1.0);
  for (double x = spacing_m; x < w - 0.5 * spacing_m; x += spacing_m) {
    for (double y = spacing_m; y < h - 0.5 * spacing_m; y += spacing_m) {
      const double cx = x + jitter(rng), cy = y + jitter(rng), r = radius(rng), p = phase(rng);
      for (int k = 0; k < 6; ++k) {
        const double a0 = p + k * std::numbers::pi / 3, a1 = p + (k + 1) * std::numbers::pi / 3;
        walls.push_back({Point(cx + r * std::cos(a0), cy + r * std::sin(a0)),
                         Point(cx + r * std::cos(a1), cy + r * std::sin(a1))});
      }
    }
  }
  return walls;
}

// The reassignment oracle: the type of the input edge with the least penalty
// for output edge (a, b), scoring every input edge (no index), with the same
// tie rule as EdgeTypeIndex. kFrontier when there are no inputs.
inline EdgeType brute_force_type(const Point& a, const Point& b, const std::vector<EdgeTypeIndex::Edge>& inputs) {
  EdgeType best_type = EdgeType::kFrontier;
  double best = std::numeric_limits<double>::infinity();
  bool any = false;
  for (const auto& e : inputs) {
    const double p = edge_match_penalty(a, b, e.a, e.b);
    if (!any || better_match(p, e.type, best, best_type)) {
      best = p;
      best_type = e.type;
      any = true;
    }
  }
  return best_type;
}

}  // namespace pex::mapping::testing
