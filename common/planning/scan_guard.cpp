#include "planning/scan_guard.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pex::planning {

double free_distance_ahead(std::span<const mapping::Point> points_robot_frame, double body_radius_m) {
  double free = std::numeric_limits<double>::infinity();
  const double r2 = body_radius_m * body_radius_m;
  for (const auto& p : points_robot_frame) {
    const double x = p.x(), y = p.y();
    if (!std::isfinite(x) || !std::isfinite(y) || x <= 0.0 || std::abs(y) >= body_radius_m) continue;
    // The disk's front meets (x, y) after it moved x - sqrt(r^2 - y^2).
    free = std::min(free, std::max(0.0, x - std::sqrt(r2 - y * y)));
  }
  return free;
}

double max_safe_speed(double free_distance_m, const ScanGuardOptions& options) {
  const double room = free_distance_m - options.margin_m;
  if (!(room > 0.0)) return 0.0;
  if (std::isinf(room)) return std::numeric_limits<double>::infinity();
  return std::sqrt(2.0 * options.max_decel_mps2 * room);
}

}  // namespace pex::planning
