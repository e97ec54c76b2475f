#include "slam/trajectory_recorder.hpp"

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

}  // namespace pex::slam
