#include "planning/live_view.hpp"

#include "mapping/blind_beams.hpp"
#include "mapping/known_walls.hpp"
#include "mapping/obstacle_band.hpp"
#include "mapping/typed_ops.hpp"

namespace pex::planning {

mapping::TypedMultiPolygon live_view(std::span<const float> ranges, double angle_min, double angle_increment,
                                     double range_min_m, const geometry::Pose2& sensor_pose,
                                     const LiveViewOptions& options, const mapping::TypedMultiPolygon* map,
                                     std::span<const std::uint8_t> blind) {
  if (!(options.range_m > 0.0)) return {};
  mapping::ScanPolygonOptions scan;
  scan.range_min_m = range_min_m;
  scan.range_max_m = 1e3;  // every return counts; farther than range_m ends the view there
  scan.free_range_m = options.range_m;
  scan.obstacle_range_m = options.range_m;
  scan.no_return_stops_at_walls = options.no_return_stops_at_walls && map;
  const auto stopped = map ? mapping::no_return_extents_in(*map, ranges, angle_min, angle_increment, sensor_pose, scan)
                           : mapping::NoReturnExtents{};
  const auto polygon = mapping::scan_to_polygon(
      ranges, angle_min, angle_increment, sensor_pose, scan,
      mapping::without_blind_beams(ranges, scan.range_min_m, scan.range_max_m, stopped.extent_m, scan.free_range_m,
                                   blind));
  if (!polygon.ok) return {};
  const mapping::TypedMultiPolygon free{polygon.polygon};
  const auto band = mapping::obstacle_band(polygon.polygon, options.obstacle_inner_m, options.obstacle_outer_m);
  mapping::MultiPolygon open = mapping::geometry_of(free);
  if (!band.empty()) {
    const auto cut = mapping::typed_difference(free, mapping::with_uniform_type(band, mapping::EdgeType::kObstacle),
                                               std::nullopt, mapping::EdgeType::kObstacle);
    if (!cut.ok) return {};
    open = mapping::geometry_of(cut.polygons);
  }
  return mapping::with_uniform_type(open, mapping::EdgeType::kObstacle);
}

mapping::TypedMultiPolygon with_live_view(const mapping::TypedMultiPolygon& map, const mapping::TypedMultiPolygon& live) {
  if (live.empty()) return map;
  mapping::TypedOpOptions options;
  // Not checked with bg::is_valid (half of a plan's CPU on ragged campus
  // maps, where the cheap test cannot vouch for the whole map and Boost
  // then checks all of it). The union only feeds the C-space's offset,
  // which Clipper computes on a 10 um grid from the rings with their
  // winding and then shrinks by the robot's radius: what the check would
  // catch (a hole put back or a polygon copied a fraction of a micrometre
  // across an edge the overlay moved onto its grid) is gone after either
  // step. A failed overlay or a result outside its area bounds is still
  // refused (typed_union checks those always), and the plan then is the
  // map's own. The map itself was checked when its message was decoded.
  options.validate = false;
  const auto united = mapping::typed_union(map, live, options);
  return united.ok ? united.polygons : map;
}

}  // namespace pex::planning
