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
  //
  // spread_corrections = false: a scan's pose is its update's pose carried
  // forward by the odometry since (what the robot knew at the scan).
  // true (offline, the whole trajectory known): the next update's
  // correction of that carried-forward pose (where the odometry says the
  // robot got to against where the update put it) is spread over the scans
  // in between, in proportion to the odometry's progress (path length, and
  // turn at linear_per_rad m per rad: the update gate's ratio, 0.5 m to
  // 0.25 rad, weighs them alike), instead of landing at once at the
  // update. The carried-forward poses then no longer accumulate the
  // odometry's error over an update interval (0.5 m, 0.25 rad) and jump.
  std::vector<TimedPose> resolve(const ParticleFilter& filter, bool spread_corrections = false,
                                 double linear_per_rad = 2.0) const;
  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    std::int64_t utime;
    std::int64_t generation;
    Pose2 odometry_from_update;  // odometry at the scan in the frame of the odometry at the update
    Pose2 odometry;              // the odometry at the scan
  };
  std::vector<Entry> entries_;
};

// `t x y theta` per pose, one a line (seconds, metres, radians; 6 decimals),
// whatever the magnitudes: the offline pose file pex-eval-slam reads.
std::string trajectory_text(const std::vector<TimedPose>& poses);

}  // namespace pex::slam
