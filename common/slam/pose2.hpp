#pragma once
// A 2D rigid pose (x, y in m, theta in rad) with the compounding operators the
// filter, the odometry carry-forward and the accuracy metric share.
#include <cmath>
#include <numbers>

namespace pex::slam {

// Wraps an angle into (-pi, pi].
inline double normalize_angle(double angle_rad) {
  if (angle_rad > -std::numbers::pi && angle_rad <= std::numbers::pi) return angle_rad;
  angle_rad = std::fmod(angle_rad, 2.0 * std::numbers::pi);
  if (angle_rad <= -std::numbers::pi) angle_rad += 2.0 * std::numbers::pi;
  if (angle_rad > std::numbers::pi) angle_rad -= 2.0 * std::numbers::pi;
  return angle_rad;
}

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};

// a ⊕ b: b expressed in a's frame, returned in the frame a is expressed in.
inline Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  return {a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m,
          normalize_angle(a.theta_rad + b.theta_rad)};
}

// The inverse: compose(a, inverse(a)) is the identity.
inline Pose2 inverse(const Pose2& a) {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  return {-c * a.x_m - s * a.y_m, s * a.x_m - c * a.y_m, normalize_angle(-a.theta_rad)};
}

// ⊖: `to` expressed in the frame of `from`, i.e. inverse(from) ⊕ to.
inline Pose2 relative(const Pose2& from, const Pose2& to) {
  const double c = std::cos(from.theta_rad);
  const double s = std::sin(from.theta_rad);
  const double dx = to.x_m - from.x_m;
  const double dy = to.y_m - from.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, normalize_angle(to.theta_rad - from.theta_rad)};
}

inline bool is_finite(const Pose2& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
}

}  // namespace pex::slam
