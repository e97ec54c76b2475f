#pragma once
// A laser scan as the filter uses it: beams already turned into points in the
// robot frame, so the matcher only transforms points by the candidate pose.
#include <cstdint>
#include <vector>

#include "geometry/pose2.hpp"

namespace pex::slam {

using geometry::Pose2;

// The raw scan: beam i is at angle_min_rad + i * angle_increment_rad in the
// sensor frame; a range that is not finite or lies outside [range_min_m,
// range_max_m) is "no return".
struct RangeScan {
  std::int64_t utime = 0;
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  Pose2 sensor_pose;  // the sensor in the robot frame
  std::vector<float> ranges_m;
};

// One usable beam in the robot frame.
struct BeamPoint {
  float hit_x_m, hit_y_m;    // the beam's end point
  float free_x_m, free_y_m;  // a point `free_offset` before the end, along the beam
};

struct ScanPoints {
  std::int64_t utime = 0;
  std::vector<BeamPoint> beams;  // usable returns only, in beam order
  // The scanner's angle between neighbouring beams (|angle_increment_rad| of
  // the RangeScan; 0 when unknown): what decimation by angle works from.
  double beam_spacing_rad = 0.0;
};

struct ScanConversionOptions {
  // Returns beyond this are not used (long beams amplify angular errors).
  double usable_range_m = 30.0;
  // Distance before the end point where the beam must have passed free space.
  double free_offset_m = 0.05;
};

struct ScanConversionStats {
  std::size_t usable = 0;
  std::size_t no_return = 0;   // beyond range_max / usable range, below range_min
  std::size_t non_finite = 0;  // NaN or inf
};

// Converts the usable returns of `scan` into robot-frame points.
ScanPoints to_scan_points(const RangeScan& scan, const ScanConversionOptions& options,
                          ScanConversionStats* stats = nullptr);

}  // namespace pex::slam
