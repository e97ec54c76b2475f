#include "kinematics/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pex::kinematics {

double DriveGeometry::counts_per_m() const {
  return counts_per_rev * gear_ratio / (2.0 * std::numbers::pi * wheel_radius_m);
}

std::string DriveGeometry::validate() const {
  auto bad = [](double v) { return !std::isfinite(v) || v <= 0.0; };
  if (bad(wheel_radius_m)) return "wheel_radius_m must be > 0";
  if (bad(wheel_base_m)) return "wheel_base_m must be > 0";
  if (bad(counts_per_rev)) return "counts_per_rev must be > 0";
  if (bad(gear_ratio)) return "gear_ratio must be > 0";
  return "";
}

WheelSpeeds to_wheels(const DriveGeometry& g, BodyVelocity body) {
  const double half = 0.5 * g.wheel_base_m * body.omega_radps;
  return {body.v_mps - half, body.v_mps + half};
}

BodyVelocity to_body(const DriveGeometry& g, WheelSpeeds w) {
  return {0.5 * (w.left_mps + w.right_mps), (w.right_mps - w.left_mps) / g.wheel_base_m};
}

VelocityLimiter::VelocityLimiter(DriveGeometry geometry, Options options)
    : geometry_(geometry), options_(options) {}

WheelSpeeds VelocityLimiter::step(BodyVelocity command, double dt_s) {
  if (!std::isfinite(command.v_mps) || !std::isfinite(command.omega_radps)) command = {};
  if (!std::isfinite(dt_s) || dt_s < 0.0) dt_s = 0.0;
  command.v_mps = std::clamp(command.v_mps, -options_.max_speed_mps, options_.max_speed_mps);
  command.omega_radps =
      std::clamp(command.omega_radps, -options_.max_omega_radps, options_.max_omega_radps);
  WheelSpeeds goal = to_wheels(geometry_, command);
  const double peak = std::max(std::abs(goal.left_mps), std::abs(goal.right_mps));
  if (peak > options_.max_wheel_speed_mps) {
    const double scale = options_.max_wheel_speed_mps / peak;  // keep the curvature
    goal.left_mps *= scale;
    goal.right_mps *= scale;
  }
  const double max_dv = options_.max_wheel_accel_mps2 * dt_s;
  // Limit both wheels by the same fraction, so a turn does not become a
  // different curve while accelerating.
  const double dl = goal.left_mps - last_.left_mps;
  const double dr = goal.right_mps - last_.right_mps;
  const double largest = std::max(std::abs(dl), std::abs(dr));
  const double fraction = largest > max_dv ? max_dv / largest : 1.0;
  last_.left_mps += dl * fraction;
  last_.right_mps += dr * fraction;
  return last_;
}

OdometryIntegrator::OdometryIntegrator(DriveGeometry geometry, Options options)
    : geometry_(geometry), options_(options) {}

bool OdometryIntegrator::update(std::int32_t left_counts, std::int32_t right_counts, std::int64_t time_us) {
  if (!have_baseline_) {
    have_baseline_ = true;
    left_ = left_counts;
    right_ = right_counts;
    time_us_ = time_us;
    state_.v_mps = 0.0;
    state_.omega_radps = 0.0;
    history_.clear();
    history_.push_back({time_us, signed_distance_m_, heading_rad_});
    return true;
  }
  // Wrap-safe difference of two int32 counters.
  auto delta = [](std::int32_t now, std::int32_t before) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(now) - static_cast<std::uint32_t>(before));
  };
  const double per_m = geometry_.counts_per_m();
  const double dl = delta(left_counts, left_) / per_m;
  const double dr = delta(right_counts, right_) / per_m;
  if (std::abs(dl) > options_.max_wheel_step_m || std::abs(dr) > options_.max_wheel_step_m) {
    ++rejected_jumps_;
    have_baseline_ = false;
    return update(left_counts, right_counts, time_us);
  }
  const double dt = static_cast<double>(time_us - time_us_) * 1e-6;
  left_ = left_counts;
  right_ = right_counts;
  time_us_ = time_us;

  const double ds = 0.5 * (dl + dr);
  const double dtheta = (dr - dl) / geometry_.wheel_base_m;
  geometry::Pose2& p = state_.pose;
  const double mid = p.theta_rad + 0.5 * dtheta;  // second-order (midpoint) integration
  const double c = std::cos(mid), s = std::sin(mid);
  p.x_m += ds * c;
  p.y_m += ds * s;
  p.theta_rad = geometry::wrap_angle(p.theta_rad + dtheta);
  signed_distance_m_ += ds;
  heading_rad_ += dtheta;
  history_.push_back({time_us, signed_distance_m_, heading_rad_});
  while (history_.size() > 2 && time_us - history_[1].time_us >= options_.velocity_window_us) history_.pop_front();
  const Sample& oldest = history_.front();
  if (time_us > oldest.time_us) {
    const double window_s = static_cast<double>(time_us - oldest.time_us) * 1e-6;
    state_.v_mps = (signed_distance_m_ - oldest.distance_m) / window_s;
    state_.omega_radps = (heading_rad_ - oldest.heading_rad) / window_s;
  } else if (dt <= 0.0) {
    state_.v_mps = 0.0;
    state_.omega_radps = 0.0;
  }
  state_.distance_m += std::abs(ds);

  // Covariance: P' = J P J^T + Q, J the motion Jacobian w.r.t. the pose, Q
  // from the step's translation and rotation noise expressed in the world frame.
  auto& P = state_.covariance;
  const double j02 = -ds * s, j12 = ds * c;
  // J = [[1,0,j02],[0,1,j12],[0,0,1]]
  std::array<double, 9> JP{};
  for (int col = 0; col < 3; ++col) {
    JP[0 * 3 + col] = P[0 * 3 + col] + j02 * P[2 * 3 + col];
    JP[1 * 3 + col] = P[1 * 3 + col] + j12 * P[2 * 3 + col];
    JP[2 * 3 + col] = P[2 * 3 + col];
  }
  std::array<double, 9> next{};
  for (int row = 0; row < 3; ++row) {
    next[row * 3 + 0] = JP[row * 3 + 0] + JP[row * 3 + 2] * j02;
    next[row * 3 + 1] = JP[row * 3 + 1] + JP[row * 3 + 2] * j12;
    next[row * 3 + 2] = JP[row * 3 + 2];
  }
  const double var_along = options_.sigma_translation_per_sqrt_m * options_.sigma_translation_per_sqrt_m *
                           std::abs(ds);
  const double var_theta = options_.sigma_rotation_per_sqrt_rad * options_.sigma_rotation_per_sqrt_rad *
                               std::abs(dtheta) +
                           options_.sigma_rotation_per_sqrt_m * options_.sigma_rotation_per_sqrt_m *
                               std::abs(ds);
  // translation noise isotropic in the plane (along and across the motion)
  next[0] += var_along;
  next[4] += var_along;
  next[8] += var_theta;
  P = next;
  return true;
}

}  // namespace pex::kinematics
