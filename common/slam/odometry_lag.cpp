#include "slam/odometry_lag.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace pex::slam {

OdometryLagEstimator::OdometryLagEstimator(const OdometryLagOptions& options) : options_(options) {
  options_.step_s = std::max(1e-4, options_.step_s);
  options_.max_lead_s = std::max(0.0, options_.max_lead_s);
  const auto half = static_cast<std::size_t>(std::llround(options_.max_lead_s / options_.step_s));
  cost_.assign(2 * half + 1, 0.0);
}

double OdometryLagEstimator::candidate_s(std::size_t k) const {
  const double half = static_cast<double>(cost_.size() / 2);
  return (static_cast<double>(k) - half) * options_.step_s;
}

void OdometryLagEstimator::add(std::int64_t from_utime, std::int64_t to_utime, double matched_turn_rad,
                               const std::function<std::optional<Pose2>(std::int64_t)>& odometry_at) {
  if (to_utime <= from_utime || !std::isfinite(matched_turn_rad)) return;
  std::vector<double> residual(cost_.size());
  for (std::size_t k = 0; k < cost_.size(); ++k) {
    const auto lead_us = static_cast<std::int64_t>(std::llround(candidate_s(k) * 1e6));
    const std::optional<Pose2> from = odometry_at(from_utime - lead_us);
    const std::optional<Pose2> to = odometry_at(to_utime - lead_us);
    if (!from || !to) return;  // every candidate judged on the same updates
    const double e = geometry::wrap_angle(matched_turn_rad - geometry::wrap_angle(to->theta_rad - from->theta_rad));
    residual[k] = std::min(e * e, options_.outlier_rad * options_.outlier_rad);
  }
  for (std::size_t k = 0; k < cost_.size(); ++k) cost_[k] += residual[k];
  ++updates_;
  estimate();
}

void OdometryLagEstimator::estimate() {
  if (!ready()) {
    lead_us_ = 0;
    return;
  }
  // The first minimum from the middle outwards: ties go to the smaller lead.
  const std::size_t mid = cost_.size() / 2;
  std::size_t best = mid;
  for (std::size_t d = 1; d <= mid; ++d)
    for (const std::size_t k : {mid - d, mid + d})
      if (cost_[k] < cost_[best]) best = k;
  double lead_s = candidate_s(best);
  if (best > 0 && best + 1 < cost_.size()) {
    const double below = cost_[best - 1], at = cost_[best], above = cost_[best + 1];
    const double curvature = below - 2.0 * at + above;
    if (curvature > 0.0) lead_s -= options_.step_s * 0.5 * (above - below) / curvature;
  }
  lead_us_ = std::abs(lead_s) < options_.min_lead_s ? 0 : static_cast<std::int64_t>(std::llround(lead_s * 1e6));
}

void OdometryLagEstimator::write(archive::ByteWriter& out) const {
  out.put<std::uint64_t>(cost_.size());
  for (const double c : cost_) out.put<double>(c);
  out.put<std::int32_t>(updates_);
}

void OdometryLagEstimator::read(archive::ByteReader& in) {
  const std::uint64_t count = in.get_count(sizeof(double));
  if (count != cost_.size())
    throw archive::ArchiveError("the odometry lead estimate has " + std::to_string(count) +
                                " candidates, this configuration " + std::to_string(cost_.size()));
  for (double& c : cost_) c = in.get<double>();
  updates_ = in.get<std::int32_t>();
  estimate();
}

}  // namespace pex::slam
