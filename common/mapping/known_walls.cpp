#include "mapping/known_walls.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "mapping/blind_beams.hpp"

namespace pex::mapping {

namespace {

double distance_to_segment(const Point& p, const Point& a, const Point& b) {
  const double ex = b.x() - a.x(), ey = b.y() - a.y();
  const double len2 = ex * ex + ey * ey;
  double t = len2 > 0.0 ? ((p.x() - a.x()) * ex + (p.y() - a.y()) * ey) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(a.x() + t * ex - p.x(), a.y() + t * ey - p.y());
}

// Every edge of `ring` within radius of center, as a -> b (reversed: b -> a).
void add_ring_edges(const Ring& ring, const std::vector<EdgeType>* types, bool reversed, const Point& center,
                    double radius_m, std::vector<KnownWall>& out) {
  for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
    if (types && (i >= types->size() || (*types)[i] != EdgeType::kObstacle)) continue;
    const Point& a = ring[i];
    const Point& b = ring[i + 1];
    if (distance_to_segment(center, a, b) > radius_m) continue;
    out.push_back(reversed ? KnownWall{b, a} : KnownWall{a, b});
  }
}

bool box_near(const Box& box, const Point& c, double r) {
  return c.x() + r >= box.min_corner().x() && c.x() - r <= box.max_corner().x() && c.y() + r >= box.min_corner().y() &&
         c.y() - r <= box.max_corner().y();
}

}  // namespace

std::vector<KnownWall> known_walls(const PolygonMap& map, const Point& center, double radius_m) {
  std::vector<KnownWall> walls;
  for (const auto& [key, tile] : map.tiles()) {
    if (!tile || !box_near(tile->box, center, radius_m)) continue;
    // The band's polygons have their inside on the left of their outer rings
    // (counter-clockwise) and of their holes (clockwise): reversed, on the right.
    for (const auto& band : tile->obstacles) {
      add_ring_edges(band.geometry.outer(), nullptr, true, center, radius_m, walls);
      for (const auto& hole : band.geometry.inners()) add_ring_edges(hole, nullptr, true, center, radius_m, walls);
    }
  }
  return walls;
}

std::vector<KnownWall> known_walls(const TypedMultiPolygon& map, const Point& center, double radius_m) {
  std::vector<KnownWall> walls;
  for (const auto& polygon : map) {
    // Free space on the left of each edge: what blocks is on the right as it is.
    if (!polygon.edge_types.empty())
      add_ring_edges(polygon.geometry.outer(), &polygon.edge_types[0], false, center, radius_m, walls);
    for (std::size_t h = 0; h < polygon.geometry.inners().size(); ++h)
      if (h + 1 < polygon.edge_types.size())
        add_ring_edges(polygon.geometry.inners()[h], &polygon.edge_types[h + 1], false, center, radius_m, walls);
  }
  return walls;
}

NoReturnExtents no_return_extents(std::span<const float> ranges, double angle_min, double angle_increment,
                                  const geometry::Pose2& sensor_pose, const ScanPolygonOptions& options,
                                  std::span<const KnownWall> walls) {
  NoReturnExtents result;
  const std::size_t n = ranges.size();
  if (n < 2 || walls.empty() || !std::isfinite(angle_min) || !std::isfinite(angle_increment) ||
      angle_increment == 0.0 || !geometry::is_finite(sensor_pose) || !(options.free_range_m > 0.0))
    return result;
  std::vector<char> no_return(n, 0);
  bool any = false;
  for (std::size_t i = 0; i < n; ++i) {
    no_return[i] = is_return(ranges[i], options.range_min_m, options.range_max_m) ? 0 : 1;
    any = any || no_return[i];
  }
  if (!any) return result;

  const double two_pi = 2.0 * std::numbers::pi;
  const double step = std::abs(angle_increment);
  const double sign = angle_increment > 0.0 ? 1.0 : -1.0;
  const double ox = sensor_pose.x_m, oy = sensor_pose.y_m;
  const double first = sensor_pose.theta_rad + angle_min;
  // A point's angle from the first beam, in the beams' direction, in [0, 2 pi).
  auto phase = [&](double x, double y) {
    double a = sign * (std::atan2(y - oy, x - ox) - first);
    a = std::fmod(a, two_pi);
    return a < 0.0 ? a + two_pi : a;
  };
  std::vector<double> extent(n, options.free_range_m);
  auto test_beams = [&](const KnownWall& w, double from_phase, double to_phase) {
    // Beam indices in double first: a tiny increment makes them far larger
    // than any integer (the scan_polygon fuzz finding); clamped, then cast.
    const double first_beam = std::ceil(from_phase / step - 1e-9), last_beam = std::floor(to_phase / step + 1e-9);
    if (!(first_beam <= last_beam) || !(last_beam >= 0.0) || !(first_beam <= static_cast<double>(n - 1))) return;
    const long lo = static_cast<long>(std::max(0.0, first_beam));
    const long hi = static_cast<long>(std::min(static_cast<double>(n - 1), last_beam));
    const double ex = w.b.x() - w.a.x(), ey = w.b.y() - w.a.y();
    for (long i = lo; i <= hi; ++i) {
      if (!no_return[static_cast<std::size_t>(i)]) continue;
      const double angle = first + sign * step * static_cast<double>(i);
      const double dx = std::cos(angle), dy = std::sin(angle);
      // Into the wall only: from its left side to its right (d x e > 0).
      const double denom = dx * ey - dy * ex;
      if (!(denom > 0.0)) continue;
      const double ax = w.a.x() - ox, ay = w.a.y() - oy;
      const double t = (ax * ey - ay * ex) / denom;  // along the beam
      const double s = (ax * dy - ay * dx) / denom;  // along the wall
      if (t <= 0.0 || s < -1e-9 || s > 1.0 + 1e-9) continue;
      extent[static_cast<std::size_t>(i)] = std::min(extent[static_cast<std::size_t>(i)], t);
    }
  };
  for (const auto& w : walls) {
    // A wall through the sensor subtends half a turn: a beam cannot cross it.
    if (distance_to_segment(Point(ox, oy), w.a, w.b) < 1e-9) continue;
    const double pa = phase(w.a.x(), w.a.y()), pb = phase(w.b.x(), w.b.y());
    const double lo = std::min(pa, pb), hi = std::max(pa, pb);
    if (hi - lo <= std::numbers::pi) {
      test_beams(w, lo, hi);
    } else {  // the wall spans the first beam's direction
      test_beams(w, hi, two_pi);
      test_beams(w, 0.0, lo);
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!no_return[i] || !(extent[i] < options.free_range_m)) continue;
    // Nothing is known nearer than the minimum range.
    extent[i] = std::min(std::max(extent[i], options.range_min_m), options.free_range_m);
    if (extent[i] < options.free_range_m) ++result.beams_stopped;
  }
  if (result.beams_stopped == 0) return result;
  result.extent_m.assign(extent.begin(), extent.end());
  return result;
}

namespace {

template <class Map>
NoReturnExtents extents_against(const Map& map, std::span<const float> ranges, double angle_min,
                                double angle_increment, const geometry::Pose2& sensor_pose,
                                const ScanPolygonOptions& options) {
  // Most scans have a return on every beam: then no wall is looked for.
  if (!options.no_return_stops_at_walls || !geometry::is_finite(sensor_pose) ||
      count_returns(ranges, options.range_min_m, options.range_max_m) == static_cast<int>(ranges.size()))
    return {};
  const auto walls = known_walls(map, {sensor_pose.x_m, sensor_pose.y_m}, options.free_range_m);
  return no_return_extents(ranges, angle_min, angle_increment, sensor_pose, options, walls);
}

template <class Map>
ScanPolygonResult polygon_against(const Map& map, std::span<const float> ranges, double angle_min,
                                  double angle_increment, const geometry::Pose2& sensor_pose,
                                  const ScanPolygonOptions& options, int* beams_stopped, BlindBeams* blind) {
  const auto stopped = extents_against(map, ranges, angle_min, angle_increment, sensor_pose, options);
  if (beams_stopped) *beams_stopped = stopped.beams_stopped;
  if (!blind) return scan_to_polygon(ranges, angle_min, angle_increment, sensor_pose, options, stopped.extent_m);
  blind->observe(ranges, options.range_min_m, options.range_max_m, stopped.extent_m, options.free_range_m);
  const auto extents =
      blind->extents(ranges, options.range_min_m, options.range_max_m, stopped.extent_m, options.free_range_m);
  return scan_to_polygon(ranges, angle_min, angle_increment, sensor_pose, options, extents);
}

}  // namespace

NoReturnExtents no_return_extents_in(const PolygonMap& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options) {
  return extents_against(map, ranges, angle_min, angle_increment, sensor_pose, options);
}

NoReturnExtents no_return_extents_in(const TypedMultiPolygon& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options) {
  return extents_against(map, ranges, angle_min, angle_increment, sensor_pose, options);
}

ScanPolygonResult scan_to_polygon_in(const PolygonMap& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options, int* beams_stopped, BlindBeams* blind) {
  return polygon_against(map, ranges, angle_min, angle_increment, sensor_pose, options, beams_stopped, blind);
}

ScanPolygonResult scan_to_polygon_in(const TypedMultiPolygon& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options, int* beams_stopped, BlindBeams* blind) {
  return polygon_against(map, ranges, angle_min, angle_increment, sensor_pose, options, beams_stopped, blind);
}

}  // namespace pex::mapping
