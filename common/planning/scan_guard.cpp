#include "planning/scan_guard.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>

#include "geometry/angle.hpp"
#include "geometry/point.hpp"
#include "mapping/known_walls.hpp"
#include "mapping/scan_polygon.hpp"

namespace pex::planning {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
// Two walls' directions this close (sine of 3 deg) are one straight wall.
constexpr double kStraightSine = 0.05;
// A wall's line must pass this much short of the next return for a bend.
constexpr double kBendM = 0.001;
// At most this many returns fit a wall's direction (an LMS1xx has 38 within
// 0.10 m of a wall 0.3 m away): a scan of many beams packed close together
// would otherwise cost the square of its size.
constexpr std::size_t kMaxFitReturns = 48;
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

// The unit direction of a wall at its end `last`, pointing out of the wall
// (away from its other returns): the principal axis of the returns in
// `wall`, or none when they are too few to have one.
std::optional<std::array<double, 2>> wall_direction(std::span<const mapping::Point> wall,
                                                    const mapping::Point& last) {
  if (wall.size() < 3) return std::nullopt;
  double mx = 0.0, my = 0.0;
  for (const auto& p : wall) mx += p.x(), my += p.y();
  mx /= static_cast<double>(wall.size());
  my /= static_cast<double>(wall.size());
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (const auto& p : wall) {
    const double dx = p.x() - mx, dy = p.y() - my;
    sxx += dx * dx, sxy += dx * dy, syy += dy * dy;
  }
  const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  double ux = std::cos(angle), uy = std::sin(angle);
  if (ux * (last.x() - mx) + uy * (last.y() - my) < 0.0) ux = -ux, uy = -uy;
  return std::array<double, 2>{ux, uy};
}

}  // namespace

std::vector<float> ranges_with_map_walls(std::span<const float> ranges, double angle_min, double angle_increment,
                                         double range_min, double range_max, const geometry::Pose2& sensor_in_map,
                                         const mapping::TypedMultiPolygon& map, double reach_m, int* filled,
                                         mapping::BlindBeams* blind) {
  std::vector<float> out(ranges.begin(), ranges.end());
  if (filled) *filled = 0;
  if (!(reach_m > 0.0)) return out;
  mapping::ScanPolygonOptions o;
  o.range_min_m = range_min;
  o.range_max_m = range_max;
  o.free_range_m = reach_m;
  o.no_return_stops_at_walls = true;
  const auto stopped = mapping::no_return_extents_in(map, ranges, angle_min, angle_increment, sensor_in_map, o);
  if (blind) blind->observe(ranges, range_min, range_max, stopped.extent_m, reach_m);
  for (std::size_t i = 0; i < stopped.extent_m.size(); ++i)
    if (!mapping::is_return(ranges[i], range_min, range_max) && stopped.extent_m[i] < reach_m)
      out[i] = stopped.extent_m[i];
  if (filled) *filled = stopped.beams_stopped;
  return out;
}

std::vector<mapping::Point> guard_points(std::span<const float> ranges, double angle_min, double angle_increment,
                                         double range_min, double range_max, const geometry::Pose2& sensor_on_robot,
                                         const GuardScanOptions& options) {
  const auto n = static_cast<std::ptrdiff_t>(ranges.size());
  const auto range = [&](std::ptrdiff_t i) { return static_cast<double>(ranges[static_cast<std::size_t>(i)]); };
  const auto has_return = [&](std::ptrdiff_t i) { return mapping::is_return(range(i), range_min, range_max); };
  // Every return in the sensor's frame (NaN where a beam has none).
  std::vector<mapping::Point> beam(ranges.size(), mapping::Point(kNan, kNan));
  std::vector<mapping::Point> points;
  points.reserve(ranges.size());
  const auto angle = [&](std::ptrdiff_t i) { return angle_min + static_cast<double>(i) * angle_increment; };
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    if (!has_return(i)) continue;
    auto& p = beam[static_cast<std::size_t>(i)];
    p = mapping::Point(range(i) * std::cos(angle(i)), range(i) * std::sin(angle(i)));
    points.push_back(p);
  }
  const double reach = options.wall_end_reach_m, step = options.wall_end_step_m;
  if (reach > 0.0 && step > 0.0) {
    const auto same_wall = [&](std::ptrdiff_t i, std::ptrdiff_t j) {
      return j >= 0 && j < n && has_return(i) && has_return(j) && std::abs(range(j) - range(i)) <= options.wall_end_jump_m;
    };
    // The direction of the wall whose returns run up to beam i from the
    // side opposite to `side`, pointing on past i (none: too few returns).
    std::vector<mapping::Point> wall;
    const double fit_squared = options.wall_fit_m * options.wall_fit_m;
    const auto wall_toward = [&](std::ptrdiff_t i, std::ptrdiff_t side) {
      const auto& last = beam[static_cast<std::size_t>(i)];
      wall.assign(1, last);
      for (std::ptrdiff_t k = i - side; same_wall(k + side, k) && wall.size() < kMaxFitReturns; k -= side) {
        const auto& p = beam[static_cast<std::size_t>(k)];
        const double dx = p.x() - last.x(), dy = p.y() - last.y();
        if (dx * dx + dy * dy > fit_squared) break;
        wall.push_back(p);
      }
      return wall_direction(wall, last);
    };
    // Points from p along u, every step_m, and at `length`.
    const auto extend = [&](const mapping::Point& p, const std::array<double, 2>& u, double length) {
      for (double t = step; t < length; t += step) points.emplace_back(p.x() + t * u[0], p.y() + t * u[1]);
      points.emplace_back(p.x() + length * u[0], p.y() + length * u[1]);
    };
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      if (!has_return(i)) continue;
      const auto& here = beam[static_cast<std::size_t>(i)];
      for (const std::ptrdiff_t side : {-1, +1}) {
        // A wall's end: the beam beside it has no return, or one a step
        // deeper. Beyond the scan's first and last beams nothing is known.
        const std::ptrdiff_t beside = i + side;
        if (beside < 0 || beside >= n) continue;
        if (has_return(beside) && range(beside) - range(i) <= options.wall_end_jump_m) continue;
        auto direction = wall_toward(i, side);
        if (!direction) {
          // Too few returns for a direction: across the beam, toward the gap.
          const double toward = (angle_increment >= 0.0 ? 1.0 : -1.0) * static_cast<double>(side);
          direction = std::array<double, 2>{-std::sin(angle(i)) * toward, std::cos(angle(i)) * toward};
        }
        extend(here, *direction, reach);
      }
      // A convex corner between this return and the next of the same wall:
      // the laser's rays cut it, the returns on either side lie behind it.
      // Where both walls have a direction, the corner is where their lines
      // meet; where one has, it lies between the two beams, so no farther
      // along that wall than where its line crosses the other beam's ray
      // (and short of that beam's return, or the walls bend away). Each wall
      // goes on to the corner, up to the reach.
      if (i + 1 >= n || !same_wall(i, i + 1)) continue;
      const auto& next = beam[static_cast<std::size_t>(i + 1)];
      const auto u = wall_toward(i, +1), w = wall_toward(i + 1, -1);
      if (u && w) {
        const double across = (*u)[0] * (*w)[1] - (*u)[1] * (*w)[0];
        if (std::abs(across) < kStraightSine) continue;  // one straight wall
        // here + t u = next + s w.
        const double dx = next.x() - here.x(), dy = next.y() - here.y();
        const double t = (dx * (*w)[1] - dy * (*w)[0]) / across;
        const double s = (dx * (*u)[1] - dy * (*u)[0]) / across;
        if (!(t > 0.0) || !(s > 0.0)) continue;
        const double cx = here.x() + t * (*u)[0], cy = here.y() + t * (*u)[1];
        const double corner_side = dx * (cy - here.y()) - dy * (cx - here.x());
        const double laser_side = dx * (0.0 - here.y()) - dy * (0.0 - here.x());
        if (corner_side * laser_side <= 0.0) continue;  // concave: the walls lie beyond the returns' line
        extend(here, *u, std::min(t, reach));
        extend(next, *w, std::min(s, reach));
        continue;
      }
      for (const std::ptrdiff_t side : {-1, +1}) {
        const std::ptrdiff_t from = side > 0 ? i : i + 1, to = from + side;
        const auto& direction = side > 0 ? u : w;
        if (!direction) continue;
        const auto& p = beam[static_cast<std::size_t>(from)];
        const double dx = std::cos(angle(to)), dy = std::sin(angle(to));
        const double across = dx * (*direction)[1] - dy * (*direction)[0];
        if (std::abs(across) < 1e-9) continue;  // along the ray
        const double t = -(dx * p.y() - dy * p.x()) / across;
        const double at_range = dx * (p.x() + t * (*direction)[0]) + dy * (p.y() + t * (*direction)[1]);
        if (t > 0.0 && at_range > 0.0 && at_range < range(to) - kBendM) extend(p, *direction, std::min(t, reach));
      }
    }
  }
  const geometry::PoseTransform to_robot(sensor_on_robot);
  for (auto& p : points) p = to_robot(p);
  return points;
}

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
