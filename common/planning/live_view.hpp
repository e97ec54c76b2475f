#pragma once
// The newest scan, opening the planning map where the laser sees free space
// now. The polygon map keeps every obstacle band it was ever given: a scan
// inserted at a pose a few degrees off (SLAM, intel missions of 2026-11-26),
// or a person standing in a doorway, leaves a band across a door, and the
// configuration space stays cut there for good — the robot was shut in a room
// with 48 frontiers "without a path" while its laser saw through the door. The
// live view is that scan's free polygon, near the robot only, minus the band
// of its own returns: united into the planning map it reopens what the laser
// sees open now, as a navigation stack's obstacle layer is cleared by the
// beams of the newest scan. It only says where the robot may drive (the
// C-space, plan_exploration's `passable`): the frontiers stay the map's, or
// a frontier edge the view covers before the mapper has the scan would
// vanish and the mission could end early. The scan guard stays in charge of
// what the laser sees in the way. Pure: no clock, no I/O.
#include <cstdint>
#include <span>

#include "mapping/scan_polygon.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct LiveViewOptions {
  // Returns farther than this, and beams without a return, end the live view
  // at this range (0: no live view). Near the robot a pose error moves the
  // view least.
  double range_m = 0.0;
  // The band cut around the scan's own returns, as the mapper's (polygon_mapper [map]).
  double obstacle_inner_m = 0.02;
  double obstacle_outer_m = 0.10;
  // A beam without a return opens the view only up to the first wall of the
  // planning map it runs into (known_walls.hpp): a laser blind in one sector
  // must not reopen the walls there for the planner. A return past a wall
  // still opens it (the laser sees through: a door opened).
  bool no_return_stops_at_walls = true;
};

// The live view of one scan (ranges as in LIDAR_SCAN, the sensor's pose in the
// map frame), every edge typed obstacle; empty when off or when the scan gives
// no polygon. `map`: the planning map the view will be united into, whose
// walls stop the beams without a return (no_return_stops_at_walls); null:
// none known. `blind`: per beam, 1 where the laser is blind
// (mapping::BlindBeams::mask; empty: none), a beam that opens nothing.
mapping::TypedMultiPolygon live_view(std::span<const float> ranges, double angle_min, double angle_increment,
                                     double range_min_m, const geometry::Pose2& sensor_pose,
                                     const LiveViewOptions& options, const mapping::TypedMultiPolygon* map = nullptr,
                                     std::span<const std::uint8_t> blind = {});

// `map` with `live` united in; `map` itself when `live` is empty or the union
// fails (the plan then is the map's own).
mapping::TypedMultiPolygon with_live_view(const mapping::TypedMultiPolygon& map, const mapping::TypedMultiPolygon& live);

}  // namespace pex::planning
