#include "slam/odometry_drift.hpp"

#include <algorithm>
#include <cmath>

namespace pex::slam {

OdometryDrift::OdometryDrift(const OdometryDriftOptions& options) : options_(options) {}

bool OdometryDrift::observe(double odometry_forward_m, double odometry_turn_rad, double matched_turn_rad) {
  const double d = odometry_forward_m;
  const double t = odometry_turn_rad;
  const double residual = geometry::wrap_angle(matched_turn_rad - odometry_turn_rad);
  if (!std::isfinite(d) || !std::isfinite(t) || !std::isfinite(residual) ||
      std::abs(residual) > options_.max_step_residual_rad) {
    ++refused_;
    return false;
  }
  const double f = options_.forgetting;
  a_dd_ = f * a_dd_ + d * d;
  a_dt_ = f * a_dt_ + d * t;
  a_tt_ = f * a_tt_ + t * t;
  b_d_ = f * b_d_ + d * residual;
  b_t_ = f * b_t_ + t * residual;
  ++observations_;
  solve();
  return true;
}

void OdometryDrift::solve() {
  // The ridge is what prior_travel_m / prior_turn_rad of steps showing no
  // drift would add (the sum of d^2 over that travel in steps of one metre
  // is prior_travel_m; likewise for turning). It is not forgotten: a base
  // that only ever drives arcs shows only the sum of its drift and turn
  // scale, and the ridge keeps the direction it never shows near 0.
  const double m00 = a_dd_ + options_.prior_travel_m;
  const double m11 = a_tt_ + options_.prior_turn_rad;
  const double m01 = a_dt_;
  const double det = m00 * m11 - m01 * m01;
  if (!(det > 0.0)) return;
  const double drift = (m11 * b_d_ - m01 * b_t_) / det;
  const double scale = (m00 * b_t_ - m01 * b_d_) / det;
  drift_rad_per_m_ = std::clamp(drift, -options_.max_drift_rad_per_m, options_.max_drift_rad_per_m);
  turn_scale_ = std::clamp(scale, -options_.max_turn_scale, options_.max_turn_scale);
}

geometry::Pose2 OdometryDrift::correct(const geometry::Pose2& odometry_step) const {
  if (!options_.correct) return odometry_step;
  geometry::Pose2 out = odometry_step;
  const double d = odometry_step.x_m;
  out.theta_rad = geometry::wrap_angle(odometry_step.theta_rad + drift_rad_per_m_ * d +
                                       turn_scale_ * odometry_step.theta_rad);
  return out;
}

void OdometryDrift::write(archive::ByteWriter& out) const {
  for (double v : {a_dd_, a_dt_, a_tt_, b_d_, b_t_, drift_rad_per_m_, turn_scale_}) out.put<double>(v);
  out.put<std::int64_t>(observations_);
  out.put<std::int64_t>(refused_);
}

void OdometryDrift::read(archive::ByteReader& in) {
  for (double* v : {&a_dd_, &a_dt_, &a_tt_, &b_d_, &b_t_, &drift_rad_per_m_, &turn_scale_}) *v = in.get<double>();
  observations_ = in.get<std::int64_t>();
  refused_ = in.get<std::int64_t>();
}

}  // namespace pex::slam
