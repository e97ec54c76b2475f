#include "slam/scan.hpp"

#include <cmath>

namespace pex::slam {

ScanPoints to_scan_points(const RangeScan& scan, const ScanConversionOptions& options,
                          ScanConversionStats* stats) {
  ScanConversionStats local;
  ScanPoints points;
  points.utime = scan.utime;
  points.beam_spacing_rad = std::abs(scan.angle_increment_rad);
  points.beams.reserve(scan.ranges_m.size());
  const double max_range = std::min(scan.range_max_m, options.usable_range_m);
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r)) {
      ++local.non_finite;
      continue;
    }
    if (r < scan.range_min_m || r >= max_range || r <= options.free_offset_m) {
      ++local.no_return;
      continue;
    }
    const double angle = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const Pose2 hit = compose(scan.sensor_pose, {r * std::cos(angle), r * std::sin(angle), 0.0});
    const double rf = r - options.free_offset_m;
    const Pose2 free = compose(scan.sensor_pose, {rf * std::cos(angle), rf * std::sin(angle), 0.0});
    points.beams.push_back({static_cast<float>(hit.x_m), static_cast<float>(hit.y_m),
                            static_cast<float>(free.x_m), static_cast<float>(free.y_m)});
    ++local.usable;
  }
  if (stats) *stats = local;
  return points;
}

}  // namespace pex::slam
