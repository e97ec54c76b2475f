#include "planning/path_follower.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "planning/cspace.hpp"
#include "planning/exploration_planner.hpp"
#include "planning/frontier_goals.hpp"

namespace pex::planning {

namespace {

double step_toward(double current, double target, double max_step) {
  return current + std::clamp(target - current, -max_step, max_step);
}

}  // namespace

PathFollower::PathFollower(FollowerOptions options) : options_(options) {}

void PathFollower::set_path(std::vector<Point> path) {
  path_ = std::move(path);
  arc_.assign(path_.size(), 0.0);
  for (std::size_t i = 1; i < path_.size(); ++i) arc_[i] = arc_[i - 1] + distance(path_[i - 1], path_[i]);
  segment_ = 0;
  reached_ = false;
}

VelocityCommand PathFollower::update(const Pose2& pose, double dt_s) {
  dt_s = std::clamp(std::isfinite(dt_s) ? dt_s : 0.0, 0.0, 0.5);
  if (path_.empty() || reached_ || !std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) ||
      !std::isfinite(pose.theta_rad)) {
    last_ = {};
    turning_ = false;
    return last_;
  }
  const Point here(pose.x_m, pose.y_m);
  const Point& goal = path_.back();
  const double to_goal = distance(here, goal);
  if (to_goal <= options_.goal_tolerance_m) {
    reached_ = true;
    last_ = {};
    turning_ = false;
    return last_;
  }

  // Progress along the path, vertex by vertex: the robot moves on to the next
  // segment once it is within corner_tolerance_m of the current segment's end
  // vertex or has passed it. The look-ahead point never goes beyond that
  // vertex, so the robot does not cut the corner (a path bends only around
  // the C-space's reflex vertices: the inside of a bend is the obstacle side).
  while (segment_ + 2 < path_.size()) {
    const Point& a = path_[segment_];
    const Point& v = path_[segment_ + 1];
    const double len = distance(a, v);
    const double t = len > 0.0 ? ((here.x() - a.x()) * (v.x() - a.x()) + (here.y() - a.y()) * (v.y() - a.y())) /
                                     (len * len)
                               : 1.0;
    if (distance(here, v) > options_.corner_tolerance_m && t < 1.0) break;
    ++segment_;
  }
  double along = 0.0;  // arc length of the robot's closest point on the current segment
  double vertex_arc = 0.0;
  if (path_.size() >= 2) {
    const Point q = closest_point_on_segment(here, path_[segment_], path_[segment_ + 1]);
    along = arc_[segment_] + distance(path_[segment_], q);
    vertex_arc = arc_[segment_ + 1];
  }
  const double total = arc_.back();
  const Point target = path_.size() >= 2 ? point_at_arc_length(path_, std::min(along + options_.lookahead_m, vertex_arc))
                                          : goal;
  const double dx = target.x() - pose.x_m, dy = target.y() - pose.y_m;
  const double lookahead = std::hypot(dx, dy);
  const double heading_error = lookahead > 1e-9 ? geometry::wrap_angle(std::atan2(dy, dx) - pose.theta_rad) : 0.0;

  if (std::abs(heading_error) > options_.turn_in_place_rad) turning_ = true;
  if (turning_ && std::abs(heading_error) < options_.turn_in_place_exit_rad) turning_ = false;

  VelocityCommand wanted;
  if (turning_) {
    wanted.omega_radps =
        std::clamp(options_.turn_gain_per_s * heading_error, -options_.max_omega_radps, options_.max_omega_radps);
  } else {
    // Pure pursuit: the arc through the look-ahead point.
    const double curvature = lookahead > 1e-9 ? 2.0 * std::sin(heading_error) / lookahead : 0.0;
    const double remaining = std::max(0.0, total - along);
    // Brake so as to arrive at the tolerance circle at creeping speed.
    const double braking = std::sqrt(
        2.0 * options_.max_accel_mps2 * std::max(0.0, std::min(remaining, to_goal) - options_.goal_tolerance_m));
    double v = std::min(options_.max_speed_mps, braking);
    if (std::abs(curvature) > 1e-9) v = std::min(v, options_.max_omega_radps / std::abs(curvature));
    v = std::max(v, std::min(options_.min_speed_mps, options_.max_speed_mps));
    wanted.v_mps = v;
    wanted.omega_radps = std::clamp(curvature * v, -options_.max_omega_radps, options_.max_omega_radps);
  }
  last_.v_mps = step_toward(last_.v_mps, wanted.v_mps, options_.max_accel_mps2 * dt_s);
  last_.omega_radps = step_toward(last_.omega_radps, wanted.omega_radps, options_.max_angular_accel_radps2 * dt_s);
  return last_;
}

VelocityCommand PathFollower::turn_to(const Pose2& pose, double heading_rad, double dt_s) {
  dt_s = std::clamp(std::isfinite(dt_s) ? dt_s : 0.0, 0.0, 0.5);
  const double error = geometry::wrap_angle(heading_rad - pose.theta_rad);
  const double wanted =
      std::clamp(options_.turn_gain_per_s * error, -options_.max_omega_radps, options_.max_omega_radps);
  last_.v_mps = step_toward(last_.v_mps, 0.0, options_.max_accel_mps2 * dt_s);
  last_.omega_radps = step_toward(last_.omega_radps, wanted, options_.max_angular_accel_radps2 * dt_s);
  return last_;
}

std::vector<Point> way_back(const std::vector<Point>& trail, double max_length_m) {
  std::vector<Point> way;
  if (trail.size() < 2) return way;
  way.push_back(trail.back());
  double length = 0.0;
  for (std::size_t k = trail.size() - 1; k-- > 0 && length < max_length_m;) {
    length += distance(trail[k + 1], trail[k]);
    way.push_back(trail[k]);
  }
  return way;
}

}  // namespace pex::planning
