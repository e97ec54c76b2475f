#include "slam/trajectory_recorder.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace pex::slam {

void TrajectoryRecorder::record(std::int64_t scan_utime, const ParticleFilter& filter,
                                const Pose2& odometry) {
  if (!filter.initialized()) return;
  entries_.push_back({scan_utime, filter.generation(), relative(filter.odometry_at_update(), odometry), odometry});
}

std::vector<TimedPose> TrajectoryRecorder::resolve(const ParticleFilter& filter, bool spread_corrections,
                                                   double linear_per_rad) const {
  const std::vector<Pose2> updates = filter.best_trajectory();
  std::vector<TimedPose> poses;
  poses.reserve(entries_.size());
  auto progress = [linear_per_rad](const Pose2& a, const Pose2& b) {
    const Pose2 step = relative(a, b);
    return std::hypot(step.x_m, step.y_m) + linear_per_rad * std::abs(step.theta_rad);
  };
  std::size_t i = 0;
  while (i < entries_.size()) {
    // The scans of one update interval: entries [i, end) share a generation.
    const std::int64_t g = entries_[i].generation;
    std::size_t end = i + 1;
    while (end < entries_.size() && entries_[end].generation == g) ++end;
    if (g < 0 || static_cast<std::size_t>(g) >= updates.size()) {
      i = end;
      continue;
    }
    const Pose2& update = updates[static_cast<std::size_t>(g)];
    // The next update's correction, where there is one: the entry at `end`
    // is the scan that made update g + 1 (its odometry is that update's).
    bool spread = spread_corrections && end < entries_.size() && entries_[end].generation == g + 1 &&
                  static_cast<std::size_t>(g + 1) < updates.size();
    Pose2 correction;
    std::vector<double> along(end - i, 0.0);
    double total = 0.0;
    if (spread) {
      const Pose2 carried = compose(update, relative(entries_[i].odometry, entries_[end].odometry));
      correction = relative(carried, updates[static_cast<std::size_t>(g + 1)]);
      for (std::size_t k = i + 1; k <= end; ++k) {
        total += progress(entries_[k - 1].odometry, entries_[k].odometry);
        if (k < end) along[k - i] = total;
      }
      spread = total > 0.0;
    }
    for (std::size_t k = i; k < end; ++k) {
      const Entry& e = entries_[k];
      Pose2 pose = compose(update, e.odometry_from_update);
      if (spread) {
        const double f = along[k - i] / total;
        pose = compose(pose, {f * correction.x_m, f * correction.y_m, f * correction.theta_rad});
      }
      poses.push_back({e.utime, pose});
    }
    i = end;
  }
  return poses;
}

std::string trajectory_text(const std::vector<TimedPose>& poses) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::fixed << std::setprecision(6);
  for (const TimedPose& p : poses)
    out << static_cast<double>(p.utime) * 1e-6 << ' ' << p.pose.x_m << ' ' << p.pose.y_m << ' ' << p.pose.theta_rad << '\n';
  return out.str();
}

}  // namespace pex::slam
