#pragma once
// The rigid motion that best maps one set of points onto another, in the
// least-squares sense (the 2D case of Horn's / Umeyama's closed form, without
// scale). Evaluation uses it to tell a map that is consistent but turned as a
// whole (a heading error at the start) from one that is bent.
#include <cmath>
#include <optional>
#include <span>

#include "geometry/point.hpp"
#include "geometry/pose2.hpp"

namespace pex::geometry {

// The pose T minimising sum |T(from[i]) - to[i]|^2 over corresponding points;
// nullopt if the spans differ in size or hold fewer than two points.
inline std::optional<Pose2> best_rigid_fit(std::span<const Point> from, std::span<const Point> to) {
  if (from.size() != to.size() || from.size() < 2) return std::nullopt;
  const double n = static_cast<double>(from.size());
  double fx = 0.0, fy = 0.0, tx = 0.0, ty = 0.0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    fx += from[i].x(), fy += from[i].y(), tx += to[i].x(), ty += to[i].y();
  }
  fx /= n, fy /= n, tx /= n, ty /= n;
  // The rotation maximising sum (to - t̄) . R (from - f̄): angle of (sum of
  // dot products, sum of cross products).
  double dot = 0.0, cross = 0.0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const double ax = from[i].x() - fx, ay = from[i].y() - fy;
    const double bx = to[i].x() - tx, by = to[i].y() - ty;
    dot += ax * bx + ay * by;
    cross += ax * by - ay * bx;
  }
  const double theta = std::atan2(cross, dot);
  const double c = std::cos(theta), s = std::sin(theta);
  return Pose2{tx - (c * fx - s * fy), ty - (s * fx + c * fy), theta};
}

}  // namespace pex::geometry
