#include "slam/odometry_sync.hpp"

#include <algorithm>

namespace pex::slam {

bool OdometrySync::possible_step(const Reading& from, const Reading& to) const {
  const StepLimits& l = options_.limits;
  const double t_s = std::max(l.min_interval_s, std::abs(static_cast<double>(to.utime - from.utime)) * 1e-6);
  const Pose2 step = relative(from.raw, to.raw);
  return std::hypot(step.x_m, step.y_m) <= l.max_speed_mps * t_s + l.slack_m &&
         std::abs(step.theta_rad) <= l.max_omega_radps * t_s + l.slack_rad;
}

void OdometrySync::reset_frame(const Reading& first_of_new_frame) {
  // The robot did not move while the odometry restarted: the new frame's first
  // reading is where the last accepted one put it.
  frame_ = compose(odometry_.back().second, inverse(first_of_new_frame.raw));
  ++odometry_resets_;
}

void OdometrySync::store(const Reading& reading) {
  if (!odometry_.empty() && reading.utime < odometry_.back().first) ++out_of_order_odometry_;
  newest_odometry_utime_ = odometry_.empty() ? reading.utime : std::max(newest_odometry_utime_, reading.utime);
  odometry_.emplace_back(reading.utime, compose(frame_, reading.raw));
  while (odometry_.size() > options_.history) odometry_.pop_front();
  last_accepted_ = reading;
}

bool OdometrySync::add_odometry(std::int64_t utime, const Pose2& pose, double heading_variance_rad2) {
  why_.clear();
  const StepLimits& l = options_.limits;
  if (!is_finite(pose) || std::abs(pose.x_m) > l.max_abs_coordinate_m || std::abs(pose.y_m) > l.max_abs_coordinate_m) {
    ++refused_odometry_;
    why_ = "odometry pose is not finite or not on this planet";
    return false;
  }
  const Reading reading{utime, pose, heading_variance_rad2};
  if (l.enabled && last_accepted_ && std::isfinite(heading_variance_rad2) &&
      std::isfinite(last_accepted_->heading_variance_rad2) &&
      heading_variance_rad2 < last_accepted_->heading_variance_rad2) {
    held_.reset();
    reset_frame(reading);
    store(reading);
    return true;
  }
  if (!l.enabled || !last_accepted_ || possible_step(*last_accepted_, reading)) {
    held_.reset();  // whatever was held was an outlier
    store(reading);
    return true;
  }
  if (held_ && possible_step(*held_, reading)) {
    // Two readings agree on a new frame: the odometry was reset. The held one
    // is where the robot was last seen (it did not move while the odometry
    // restarted); the estimate stays where it was.
    reset_frame(*held_);
    store(*held_);
    held_.reset();
    store(reading);
    return true;
  }
  ++impossible_steps_;
  const Pose2 step = relative(last_accepted_->raw, pose);
  why_ = "odometry step of " + std::to_string(std::hypot(step.x_m, step.y_m)) + " m, " +
         std::to_string(std::abs(step.theta_rad)) + " rad in " +
         std::to_string(std::abs(static_cast<double>(utime - last_accepted_->utime)) * 1e-6) +
         " s is not possible; held (a next reading that agrees with it makes it an odometry reset)";
  held_ = reading;
  return false;
}

std::optional<Pose2> OdometrySync::newest_pose() const {
  if (odometry_.empty()) return std::nullopt;
  return odometry_.back().second;
}

bool OdometrySync::add_scan(RangeScan scan) {
  if (odometry_.empty()) {
    ++dropped_scans_;
    return false;
  }
  scans_.push_back(std::move(scan));
  return true;
}

Pose2 OdometrySync::pose_at(std::int64_t utime) const {
  // Newest first: the reading of exactly this time, else the newest consecutive
  // pair (in arrival order) whose times enclose it.
  for (auto it = odometry_.rbegin(); it != odometry_.rend(); ++it)
    if (it->first == utime) return it->second;
  for (std::size_t i = odometry_.size() - 1; i > 0; --i) {
    const auto& before = odometry_[i - 1];
    const auto& after = odometry_[i];
    if (before.first < utime && utime < after.first) {
      const double f = static_cast<double>(utime - before.first) /
                       static_cast<double>(after.first - before.first);
      const Pose2 step = relative(before.second, after.second);
      return compose(before.second, {f * step.x_m, f * step.y_m, f * step.theta_rad});
    }
  }
  return odometry_.back().second;
}

std::vector<PairedScan> OdometrySync::take_ready() {
  std::vector<PairedScan> ready;
  while (!scans_.empty()) {
    const RangeScan& scan = scans_.front();
    const bool odometry_caught_up = newest_odometry_utime_ >= scan.utime;
    const bool waited_too_long = scans_.back().utime - scan.utime > options_.max_wait_us ||
                                 scans_.size() > options_.max_buffered_scans;
    if (!odometry_caught_up && !waited_too_long) break;
    const Pose2 odometry = pose_at(scan.utime);
    ready.push_back({std::move(scans_.front()), odometry});
    scans_.pop_front();
  }
  return ready;
}

std::vector<PairedScan> OdometrySync::flush() {
  std::vector<PairedScan> ready;
  while (!scans_.empty()) {
    const Pose2 odometry = pose_at(scans_.front().utime);
    ready.push_back({std::move(scans_.front()), odometry});
    scans_.pop_front();
  }
  return ready;
}

}  // namespace pex::slam
