// A CARMEN log (the SLAM benchmark's text format, pex-carmen2lcm's input):
// evaluation::parse_carmen_log, line by line, then
// evaluation::correct_odometry_direction (pex-carmen2lcm's default).
//
// Input: the file's text.
// Invariants: nothing crashes; every line is a message, skipped or malformed
// (with the first error kept); every message taken is finite
// and within the options' limits (poses, stamps, ranges, velocities), its
// beam count within max_beams; the log's order
// indexes its messages exactly once each. The direction correction keeps
// every message and its time, leaves every pose finite, and changes nothing
// when it reverses no step.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "evaluation/carmen_log.hpp"
#include "evaluation/odometry_direction.hpp"
#include "fuzz_check.hpp"

namespace {

bool plausible_pose(const pex::geometry::Pose2& p, double limit) {
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

  CarmenLog corrected = log;
  const OdometryDirectionResult result = correct_odometry_direction(corrected);
  PEX_FUZZ_CHECK(corrected.lasers.size() == log.lasers.size() && corrected.odometry.size() == log.odometry.size(),
                 "direction: message count");
  PEX_FUZZ_CHECK(result.changed_laser_poses <= log.lasers.size() && result.reversed_steps < log.odometry.size() + 1,
                 "direction: counts");
  auto same = [](const pex::geometry::Pose2& a, const pex::geometry::Pose2& b) {
    return a.x_m == b.x_m && a.y_m == b.y_m && a.theta_rad == b.theta_rad;
  };
  auto finite = [](const pex::geometry::Pose2& p) {
    return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
  };
  for (std::size_t i = 0; i < log.lasers.size(); ++i) {
    const CarmenLaser& a = corrected.lasers[i];
    const CarmenLaser& b = log.lasers[i];
    PEX_FUZZ_CHECK(a.timestamp_s == b.timestamp_s && a.ranges_m == b.ranges_m, "direction: laser data");
    PEX_FUZZ_CHECK(finite(a.odometry) && finite(a.laser_pose), "direction: laser pose not finite");
    if (result.reversed_steps == 0)
      PEX_FUZZ_CHECK(same(a.odometry, b.odometry) && same(a.laser_pose, b.laser_pose), "direction: laser changed");
  }
  for (std::size_t i = 0; i < log.odometry.size(); ++i) {
    PEX_FUZZ_CHECK(corrected.odometry[i].timestamp_s == log.odometry[i].timestamp_s &&
                       finite(corrected.odometry[i].pose),
                   "direction: odometry");
    if (result.reversed_steps == 0)
      PEX_FUZZ_CHECK(same(corrected.odometry[i].pose, log.odometry[i].pose), "direction: odometry changed");
  }
  return 0;
}
