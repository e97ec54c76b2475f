#pragma once
// A beam without a return is weak evidence: the laser saw nothing out to its
// range, or it saw nothing at all. A covered or dirty part of the window, a
// cable hanging in front of it, a dark or glass surface at a grazing angle,
// an object nearer than the minimum range: each gives "no echo" on some beams
// while a wall stands a metre away. scan_to_polygon makes such a beam free
// space for free_range_m, so a laser blind in one sector would carve the
// map's walls away there, scan after scan, and the planner would then route
// the robot through them. A wall the map already holds is stronger evidence
// than a beam that saw nothing: here a beam without a return ends where it
// runs into one. Returns are untouched (a return past a wall is the laser
// seeing through it now: an opened door). Pure: no clock, no I/O.
#include <span>
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

class BlindBeams;

// A wall the map holds, as a segment a -> b with what blocks on its right: a
// beam crossing it from its left to its right side runs into the wall. (A
// beam leaving the wall's inside, as from a sensor standing in an obstacle
// band, crosses the other way and goes on.)
struct KnownWall {
  Point a, b;
};

// The obstacle layer of `map` (the band around every wall it was given,
// PolygonMap's obstacles) within radius_m of `center`: every edge of its
// tiles' band polygons near it, oriented so that the band is on its right.
// Tile-border edges count too: a band cut by a tile line goes on in the next
// tile, and the beam met it before the line.
std::vector<KnownWall> known_walls(const PolygonMap& map, const Point& center, double radius_m);

// The obstacle edges of a free-space map (a planning map as the explorer gets
// it: free interior on the left of every edge) within radius_m of `center`.
// Frontier edges are no wall: the unknown lies behind them.
std::vector<KnownWall> known_walls(const TypedMultiPolygon& map, const Point& center, double radius_m);

struct NoReturnExtents {
  // Per beam, in the order of `ranges`: how far the free space of a beam
  // without a return reaches (options.free_range_m, or where it first runs
  // into a wall, at least options.range_min_m); returns keep free_range_m
  // (scan_to_polygon does not read it for them). Empty when no beam ran
  // into a wall, or the scan is not one scan_to_polygon would take.
  std::vector<float> extent_m;
  int beams_stopped = 0;  // beams without a return that ran into a wall within free_range_m
};

// The beams of a scan (as scan_to_polygon takes it, the sensor's pose in the
// map frame) without a return, each stopped at the first of `walls` it runs
// into within options.free_range_m. Cost: each wall tests only the beams
// within the angle it subtends from the sensor.
NoReturnExtents no_return_extents(std::span<const float> ranges, double angle_min, double angle_increment,
                                  const geometry::Pose2& sensor_pose, const ScanPolygonOptions& options,
                                  std::span<const KnownWall> walls);

// no_return_extents against the walls of `map` within free_range_m of the
// sensor, when options.no_return_stops_at_walls and the scan has a beam
// without a return (else empty: most scans have a return on every beam).
NoReturnExtents no_return_extents_in(const PolygonMap& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options);
NoReturnExtents no_return_extents_in(const TypedMultiPolygon& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options);

// scan_to_polygon into `map`: with options.no_return_stops_at_walls, the
// beams without a return stopped at map's walls first (known_walls within
// free_range_m, no_return_extents); `beams_stopped`, if given, counts them.
// With `blind` (blind_beams.hpp), the scan is observed by it first and its
// blind beams give no free space. What the mapper inserts, and what the
// benchmarks' emulated missions do as it.
ScanPolygonResult scan_to_polygon_in(const PolygonMap& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options, int* beams_stopped = nullptr,
                                     BlindBeams* blind = nullptr);
// The same against a free-space map's obstacle edges (the explorer's live view).
ScanPolygonResult scan_to_polygon_in(const TypedMultiPolygon& map, std::span<const float> ranges, double angle_min,
                                     double angle_increment, const geometry::Pose2& sensor_pose,
                                     const ScanPolygonOptions& options, int* beams_stopped = nullptr,
                                     BlindBeams* blind = nullptr);

}  // namespace pex::mapping
