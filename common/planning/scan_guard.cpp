#include "planning/scan_guard.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/angle.hpp"

namespace pex::planning {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Below this curvature (a radius of 1000 km) the arc is a straight line: the
// circle's formulas lose their digits there.
constexpr double kStraightCurvature = 1e-6;
// A point the body already overlaps may come this much nearer while the robot
// drives along it (sliding off a wall it grazed).
constexpr double kTouchingSlackM = 0.005;
// The speed model counts a robot this slow as stopped (rounding of the
// braking steps leaves a few 1e-17 m/s otherwise).
constexpr double kStoppedMps = 1e-3;

double straight_free_distance(double x, double y, double r) {
  if (x <= 0.0 || std::abs(y) >= r) return kInf;  // behind or beside the swept band
  // The disk's front meets (x, y) after it moved x - sqrt(r^2 - y^2).
  return std::max(0.0, x - std::sqrt(r * r - y * y));
}

// The disk's centre runs on the circle of radius |R| about C = (0, R),
// R = 1 / kappa, starting at the origin. A point p at distance rho from C is
// within r of the centre where the angle at C between the centre and p is at
// most D, cos D = (R^2 + rho^2 - r^2) / (2 |R| rho); the centre turns by
// kappa per metre, so it meets p after turning (angle to p) - D.
double arc_free_distance(double x, double y, double kappa, double r) {
  const double radius = 1.0 / kappa;  // signed
  const double abs_radius = std::abs(radius);
  const double dx = x, dy = y - radius;
  const double rho = std::hypot(dx, dy);
  if (std::abs(rho - abs_radius) >= r) return kInf;  // outside the swept annulus
  if (rho < 1e-12) return kInf;                      // the centre of turning, not within r (caller checked)
  const double cos_d = std::clamp((radius * radius + rho * rho - r * r) / (2.0 * abs_radius * rho), -1.0, 1.0);
  const double half_width = std::acos(cos_d);
  // Angles about C, counted in the direction of travel from the robot's own.
  const double sign = kappa > 0.0 ? 1.0 : -1.0;
  const double start = std::atan2(-radius, 0.0);
  const double to_point = geometry::wrap_angle_positive(sign * (std::atan2(dy, dx) - start));
  return std::max(0.0, to_point - half_width) * abs_radius;
}

}  // namespace

double free_distance_along_arc(std::span<const mapping::Point> points_robot_frame, double curvature_per_m,
                               double body_radius_m) {
  double free = kInf;
  const double r = body_radius_m;
  const bool straight = !(std::abs(curvature_per_m) >= kStraightCurvature);
  for (const auto& p : points_robot_frame) {
    const double x = p.x(), y = p.y();
    if (!std::isfinite(x) || !std::isfinite(y)) continue;
    if (x * x + y * y < r * r) {
      // Touching already. Driving on closes in on the point only when it lies
      // ahead of the centre (the way starts along +x whatever the curvature),
      // and then by |p| - |y| at most: a point behind or beside the centre
      // must not hold the robot where it is, or a robot that grazed a wall
      // could never drive away from it.
      if (x > 0.0 && std::sqrt(x * x + y * y) - std::abs(y) > kTouchingSlackM) return 0.0;
      continue;
    }
    free = std::min(free, straight ? straight_free_distance(x, y, r) : arc_free_distance(x, y, curvature_per_m, r));
  }
  return free;
}

double free_distance_ahead(std::span<const mapping::Point> points_robot_frame, double body_radius_m) {
  return free_distance_along_arc(points_robot_frame, 0.0, body_radius_m);
}

double max_safe_speed(double free_distance_m, const ScanGuardOptions& options) {
  const double room = free_distance_m - options.margin_m;
  if (!(room > 0.0)) return 0.0;
  if (std::isinf(room)) return kInf;
  const double a = options.max_decel_mps2, t = std::max(0.0, options.latency_s);
  return a * (std::sqrt(t * t + 2.0 * room / a) - t);
}

double ScanGuard::braked_speed(double step_s) const {
  const double braked = speed_mps_ - std::max(0.0, step_s) * options_.max_decel_mps2;
  return braked > kStoppedMps ? braked : 0.0;
}

void ScanGuard::sent(double v_mps, double step_s) { speed_mps_ = std::max({0.0, v_mps, braked_speed(step_s)}); }

GuardedCommand ScanGuard::command(std::span<const mapping::Point> points_robot_frame, double v_mps, double omega_radps,
                                  double since_scan_s, double step_s) {
  GuardedCommand out{v_mps, omega_radps, false};
  if (v_mps > 0.0) {
    const double curvature = omega_radps / v_mps;
    // The robot drove on since the scan came in, at most at the speed it may have.
    const double used = std::max(0.0, since_scan_s) * speed_mps_;
    const double rolling = braked_speed(step_s);
    const double bare =
        max_safe_speed(free_distance_along_arc(points_robot_frame, curvature, options_.body_radius_m) - used, options_);
    double safe = bare;
    if (options_.side_margin_m > 0.0 && safe > options_.creep_speed_mps) {
      // A wider body: where it meets a return the bare one passes beside it.
      const double wide = free_distance_along_arc(points_robot_frame, curvature,
                                                  options_.body_radius_m + options_.side_margin_m) -
                          used;
      safe = std::max(max_safe_speed(wide, options_), options_.creep_speed_mps);
    }
    if (bare < rolling) {
      out = {0.0, 0.0, true};  // no room on the new arc from the speed it has: brake on the old one
    } else if (v_mps > safe) {
      out.limited = true;
      if (safe > 0.0) {
        out.v_mps = safe;
        out.omega_radps = curvature * safe;  // the same arc, slower
      } else {
        out.v_mps = 0.0;  // blocked and stopped: turn on the spot (omega kept)
      }
    }
  } else if (v_mps == 0.0 && omega_radps != 0.0 && braked_speed(step_s) > 0.0) {
    out = {0.0, 0.0, true};  // a turn on the spot waits until the robot may have stopped
  }
  sent(out.v_mps, step_s);
  return out;
}

}  // namespace pex::planning
