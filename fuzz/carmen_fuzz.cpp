// A CARMEN log (the SLAM benchmark's text format, pex-carmen2lcm's input):
// evaluation::parse_carmen_log, line by line.
//
// Input: the file's text.
// Invariants: nothing crashes; every line is a message, skipped or malformed
// (with the first error kept); every message taken is finite
// and within the options' limits (poses, stamps, ranges, velocities), its
// beam count within max_beams; the log's order
// indexes its messages exactly once each.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "evaluation/carmen_log.hpp"
#include "fuzz_check.hpp"

namespace {

bool plausible_pose(const pex::slam::Pose2& p, double limit) {
  return std::abs(p.x_m) <= limit && std::abs(p.y_m) <= limit && std::abs(p.theta_rad) <= limit;
}

bool plausible_time(double t, const pex::evaluation::CarmenParseOptions& o) {
  return t >= 0 && t <= o.max_timestamp_s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pex::evaluation;
  const CarmenParseOptions options;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  const CarmenLog log = parse_carmen_log(in, options);
  PEX_FUZZ_CHECK(log.order.size() == log.lasers.size() + log.odometry.size(), "order");
  PEX_FUZZ_CHECK((log.malformed_lines == 0) == log.first_error.empty(), "first_error: " + log.first_error);
  std::size_t lasers = 0, odometry = 0;
  for (const auto& e : log.order) {
    if (e.is_laser) {
      PEX_FUZZ_CHECK(e.index == lasers++, "laser order");
    } else {
      PEX_FUZZ_CHECK(e.index == odometry++, "odometry order");
    }
  }
  for (const auto& l : log.lasers) {
    PEX_FUZZ_CHECK(plausible_time(l.timestamp_s, options) && std::isfinite(l.angle_min_rad) &&
                       l.angle_increment_rad > 0 && l.max_range_m > 0 && l.max_range_m <= options.max_range_m,
                   "laser numbers");
    PEX_FUZZ_CHECK(plausible_pose(l.laser_pose, options.max_abs_coordinate_m) &&
                       plausible_pose(l.odometry, options.max_abs_coordinate_m),
                   "laser poses");
    PEX_FUZZ_CHECK(!l.ranges_m.empty() && l.ranges_m.size() <= options.max_beams,
                   "beams " + std::to_string(l.ranges_m.size()));
    for (float r : l.ranges_m) PEX_FUZZ_CHECK(r >= 0 && r <= options.max_range_m, "range " + std::to_string(r));
  }
  for (const auto& o : log.odometry)
    PEX_FUZZ_CHECK(plausible_time(o.timestamp_s, options) && plausible_pose(o.pose, options.max_abs_coordinate_m) &&
                       std::abs(o.tv_mps) <= options.max_abs_velocity && std::abs(o.rv_radps) <= options.max_abs_velocity,
                   "odometry numbers");
  return 0;
}
