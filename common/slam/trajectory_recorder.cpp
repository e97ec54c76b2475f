#include "slam/trajectory_recorder.hpp"

#include <iomanip>
#include <sstream>

namespace pex::slam {

void TrajectoryRecorder::record(std::int64_t scan_utime, const ParticleFilter& filter,
                                const Pose2& odometry) {
  if (!filter.initialized()) return;
  entries_.push_back({scan_utime, filter.generation(), relative(filter.odometry_at_update(), odometry)});
}

std::vector<TimedPose> TrajectoryRecorder::resolve(const ParticleFilter& filter) const {
  const std::vector<Pose2> updates = filter.best_trajectory();
  std::vector<TimedPose> poses;
  poses.reserve(entries_.size());
  for (const Entry& e : entries_) {
    if (e.generation < 0 || static_cast<std::size_t>(e.generation) >= updates.size()) continue;
    poses.push_back({e.utime, compose(updates[static_cast<std::size_t>(e.generation)], e.odometry_from_update)});
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
