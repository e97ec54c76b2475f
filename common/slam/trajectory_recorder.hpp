#pragma once
// Records, for every scan the filter saw, what is needed to give that scan a
// pose on the final best particle's trajectory: the update generation it
// follows and the odometry since that update (scans between updates get the
// update's pose carried forward by odometry).
#include <cstdint>
#include <string>
#include <vector>

#include "slam/particle_filter.hpp"

namespace pex::slam {

struct TimedPose {
  std::int64_t utime = 0;
  Pose2 pose;
};

class TrajectoryRecorder {
 public:
  // Call after filter.process(scan, odometry); scans before the first update are ignored.
  void record(std::int64_t scan_utime, const ParticleFilter& filter, const Pose2& odometry);
  // One pose per recorded scan on the best particle's trajectory, in record order.
  std::vector<TimedPose> resolve(const ParticleFilter& filter) const;
  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    std::int64_t utime;
    std::int64_t generation;
    Pose2 odometry_from_update;  // odometry at the scan in the frame of the odometry at the update
  };
  std::vector<Entry> entries_;
};

// `t x y theta` per pose, one a line (seconds, metres, radians; 6 decimals),
// whatever the magnitudes: the offline pose file pex-eval-slam reads.
std::string trajectory_text(const std::vector<TimedPose>& poses);

}  // namespace pex::slam
