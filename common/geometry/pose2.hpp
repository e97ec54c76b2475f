#pragma once
// A 2D rigid pose and its algebra: the one pose type of every library (the
// robot in the map, the sensor on the robot, an odometry step, a map in the
// world). Modelled on Cartographer's transform::Rigid2d, as a plain aggregate:
// Pose2{x, y, theta} builds one.
//
// Conventions: a pose P "of B in A" maps coordinates in frame B to frame A:
// p_A = R(theta) p_B + (x, y). Headings are kept wrapped to (-pi, pi]
// (wrap_angle) by every operation here.
#include <cmath>

#include "geometry/angle.hpp"

namespace pex::geometry {

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};

// a ⊕ b: b expressed in a's frame, returned in the frame a is expressed in.
inline Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  return {a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m, wrap_angle(a.theta_rad + b.theta_rad)};
}

// The inverse: compose(a, inverse(a)) is the identity.
inline Pose2 inverse(const Pose2& a) {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  return {-c * a.x_m - s * a.y_m, s * a.x_m - c * a.y_m, wrap_angle(-a.theta_rad)};
}

// ⊖: `to` expressed in the frame of `from`, i.e. inverse(from) ⊕ to (computed
// directly, one rotation instead of two).
inline Pose2 relative(const Pose2& from, const Pose2& to) {
  const double c = std::cos(from.theta_rad);
  const double s = std::sin(from.theta_rad);
  const double dx = to.x_m - from.x_m;
  const double dy = to.y_m - from.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, wrap_angle(to.theta_rad - from.theta_rad)};
}

inline bool is_finite(const Pose2& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
}

}  // namespace pex::geometry
