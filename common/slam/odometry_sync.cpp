#include "slam/odometry_sync.hpp"

#include <algorithm>

namespace pex::slam {

bool OdometrySync::add_odometry(std::int64_t utime, const Pose2& pose) {
  if (!is_finite(pose)) {
    ++refused_odometry_;
    return false;
  }
  if (!odometry_.empty() && utime < odometry_.back().first) ++out_of_order_odometry_;
  newest_odometry_utime_ = odometry_.empty() ? utime : std::max(newest_odometry_utime_, utime);
  odometry_.emplace_back(utime, pose);
  while (odometry_.size() > options_.history) odometry_.pop_front();
  return true;
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
