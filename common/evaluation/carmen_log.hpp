#pragma once
// Parsing of CARMEN logs (the text format of the Kümmerle et al. 2009 SLAM
// benchmark): FLASER, ROBOTLASER1 and ODOM lines; everything else is skipped.
// Parsing only: the caller owns the stream.
#include <cstdint>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "geometry/pose2.hpp"

namespace pex::evaluation {

// One front-laser reading. Beam i is at angle_min_rad + i * angle_increment_rad
// in the laser frame; readings >= max_range_m mean "no return".
struct CarmenLaser {
  double timestamp_s = 0.0;  // ipc_timestamp
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  double max_range_m = 0.0;
  std::vector<float> ranges_m;
  geometry::Pose2 laser_pose;  // laser pose in the odometry frame, as logged
  geometry::Pose2 odometry;    // robot odometry pose when the scan was taken
};

struct CarmenOdometry {
  double timestamp_s = 0.0;  // ipc_timestamp
  geometry::Pose2 pose;
  double tv_mps = 0.0;
  double rv_radps = 0.0;
};

struct CarmenParseOptions {
  // FLASER lines carry no field of view or maximum range. The field of view is
  // taken as 180° starting at -90° (an odd beam count includes both ends, an
  // even one stops one step short of +90°, as CARMEN's SICK driver logs them).
  double flaser_field_of_view_rad = 3.141592653589793;
  // Readings at or beyond this are "no return" for FLASER lines. The benchmark's
  // logs use 50 m or 80 m (81.83) as the no-return value; a SICK LMS indoors
  // never measures near 50 m, so just below 50 m separates both.
  double flaser_max_range_m = 49.9;
  // A line announcing more beams than this is malformed (guards the allocation).
  std::size_t max_beams = 4096;
  // Numbers no robot in a building logs make the line malformed (issue 12:
  // poses of 1e308 and timestamps of -1e18 s went through to pex-carmen2lcm,
  // whose microsecond stamps they overflow): poses, velocities and ranges
  // beyond these magnitudes, timestamps outside [0, max_timestamp_s], and
  // ROBOTLASER1 angles that are not a laser's (a field of view or step not in
  // (0, 2 pi], a start angle beyond 2 pi) or a maximum range not in (0, max_range_m].
  double max_abs_coordinate_m = 1e5;  // pose x, y (and theta, in rad)
  double max_abs_velocity = 1e3;      // tv (m/s), rv (rad/s)
  double max_range_m = 1e4;           // a reading, or ROBOTLASER1's maximum range
  double max_timestamp_s = 1e10;      // the year 2286 as Unix time
};

using CarmenMessage = std::variant<CarmenLaser, CarmenOdometry>;

// Result of parsing one line.
enum class LineKind { kMessage, kSkipped, kMalformed };

// Parses one line. Returns kSkipped for comments, PARAM and unknown message
// names, kMalformed (with `error` filled) for a FLASER/ROBOTLASER1/ODOM line that
// does not parse, holds non-finite numbers or numbers beyond the options' limits.
LineKind parse_carmen_line(std::string_view line, const CarmenParseOptions& options,
                           CarmenMessage& message, std::string& error);

struct CarmenLog {
  std::vector<CarmenLaser> lasers;        // in file order
  std::vector<CarmenOdometry> odometry;   // in file order (ODOM lines only)
  // Messages in file order: index into lasers (is_laser) or odometry.
  struct Entry {
    bool is_laser;
    std::size_t index;
  };
  std::vector<Entry> order;
  std::size_t malformed_lines = 0;
  std::string first_error;  // the first malformed line's error, for the user
};

CarmenLog parse_carmen_log(std::istream& in, const CarmenParseOptions& options = {});

}  // namespace pex::evaluation
