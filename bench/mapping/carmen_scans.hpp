#pragma once
// The scans of a CARMEN log the way the mapper inserts them, for the mapping
// benchmark and stress tool: at the logged laser pose (raw odometry), a scan
// after 0.2 m or 0.25 rad of motion, ranges at the sensor's maximum as no return.
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "evaluation/carmen_log.hpp"
#include "mapping/scan_polygon.hpp"

namespace pex::bench {

// fn(ranges, laser, pose) for every such scan, until fn returns false.
// False if the log cannot be read.
template <class Fn>
bool for_each_moved_scan(const std::string& path, Fn&& fn) {
  std::ifstream in(path);
  if (!in) return false;
  const auto log = evaluation::parse_carmen_log(in);
  std::optional<geometry::Pose2> last;
  for (const auto& laser : log.lasers) {
    const geometry::Pose2& pose = laser.laser_pose;
    if (last && std::hypot(pose.x_m - last->x_m, pose.y_m - last->y_m) < 0.2 &&
        std::abs(pex::geometry::wrap_angle(pose.theta_rad - last->theta_rad)) < 0.25)
      continue;
    last = pose;
    std::vector<float> ranges = laser.ranges_m;
    for (auto& r : ranges)
      if (r >= laser.max_range_m) r = std::numeric_limits<float>::infinity();  // no return
    if (!fn(ranges, laser, pose)) break;
  }
  return true;
}

}  // namespace pex::bench
