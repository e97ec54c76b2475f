#pragma once
// How well an exploration run mapped a simulated world: the world's free
// space reachable by the robot, and the map's coverage of it, IoU with it and
// obstacle edges on walls (issue 10's benchmark). Pure geometry: no LCM, no
// I/O; worlds come in as sim::World, maps as typed polygons.
#include <optional>

#include "evaluation/obstacle_on_wall.hpp"
#include "kinematics/kinematics.hpp"
#include "mapping/edge_overlay.hpp"
#include "mapping/typed_polygon.hpp"
#include "sim/sim.hpp"

namespace pex::evaluation {

struct ReachableOptions {
  // Vertices of the polygon standing for the robot's disk (inscribed, at
  // fixed world angles k * 2 pi / n, so axis-parallel walls come out exact;
  // elsewhere an arc is off by at most r (1 - cos(pi / n)), 0.3 mm for
  // r = 0.25 m and n = 64). A multiple of 4.
  int points_per_circle = 64;
};

// The floor area the robot's body can sweep from `start`: C-free is the set
// of centre positions where the disk of radius robot_radius_m touches no wall
// segment, within the walls' bounding box grown by a margin (so a robot can
// pass round outside a building whose outside is open); its connected
// component holding start's position is dilated by the disk (Minkowski sum)
// and clipped to the walls' bounding box. Walls are lines: they have no area,
// and a room closed by walls and not reachable through a gap of at least
// 2 * robot_radius_m is not in the result.
//
// Computed as: the bounding box minus the union of per-wall capsules (united
// in a balanced cascade), the component, then that component united with the
// capsules of its boundary edges (a cascade again), every overlay through
// checked_overlay. Returns an empty multi-polygon when start lies in
// collision (no C-free component holds it) or robot_radius_m <= 0; throws
// std::runtime_error when an overlay fails (never seen on worlds/*.wkt).
mapping::MultiPolygon reachable_free_space(const sim::World& world, double robot_radius_m,
                                           const geometry::Pose2& start, const ReachableOptions& options = {});

// The C-free component holding start (robot centres), as computed on the way
// to reachable_free_space; exposed for tests and drawings.
mapping::MultiPolygon configuration_free_component(const sim::World& world, double robot_radius_m,
                                                   const geometry::Pose2& start,
                                                   const ReachableOptions& options = {});

// a op b (a minus b for kDifference) of valid multi-polygons, by the
// mapping library's edge overlay, or by Boost.Geometry when that fails; a
// result is taken only when it is valid and its area lies within what the
// operation allows (union: max(|a|, |b|)..|a| + |b|; intersection:
// 0..min(|a|, |b|); difference: |a| - |b|..|a|). nullopt when neither passes.
std::optional<mapping::MultiPolygon> checked_overlay(const mapping::MultiPolygon& a, const mapping::MultiPolygon& b,
                                                     mapping::OverlayOp op);

// Moves geometry given in the map frame into the world frame, where
// map_in_world is the pose of the map frame's origin in the world. The MAP
// message is in the SLAM / odometry frame, whose origin is the robot's start
// pose (odometry starts at 0, 0, 0 and SLAM initialises on it): pass
// world.start. A map made with pose_source = "sim_truth" is already in the
// world frame: pass the identity.
mapping::MultiPolygon to_world(const mapping::MultiPolygon& in_map, const geometry::Pose2& map_in_world);
mapping::TypedMultiPolygon to_world(const mapping::TypedMultiPolygon& in_map, const geometry::Pose2& map_in_world);

// area(map_free ∩ reachable) / area(reachable), both in the world frame.
// NaN if reachable has no area or the overlays fail (checked_overlay, and
// area(map ∩ reachable) + area(map - reachable) must equal area(map)).
double coverage(const mapping::MultiPolygon& map_free, const mapping::MultiPolygon& reachable);

// area(map_free ∩ reachable) / area(map_free ∪ reachable). NaN if both are
// empty or the overlays fail (as coverage). The union's area is
// |map| + |reachable| - |map ∩ reachable|, from the same overlay.
double iou(const mapping::MultiPolygon& map_free, const mapping::MultiPolygon& reachable);

// Everything at once: the map (free-space polygons, MAP frame) against the
// world.
//
// obstacle_band_credit_m > 0 credits the strip the mapper's obstacle band
// takes from the free space: the MAP message is the planning map, free space
// minus a band around every obstacle edge (polygon_mapper [map]
// obstacle_inner_m on the free side, obstacle_outer_m beyond the wall, so a
// thin wall seen from both sides loses obstacle_outer_m on each side). With
// the credit, reachable space within that distance of a map obstacle edge
// counts as mapped (added to the map for coverage and IoU, never outside the
// reachable space, so the map's own overreach still counts against IoU).
// Frontier edges get no credit. 0: the map as published.
//
// Where the credit is taken: near the map's obstacle edges (the benchmark's
// "band credited" columns), or near the world's walls. The second is the
// stricter score: a wall the map draws where the world has none (a ghost
// wall, from a SLAM jump) loses its band of floor, where the first would
// credit it back.
enum class CreditNear { kMapObstacleEdges, kWorldWalls };

struct MapScore {
  double explored_m2 = 0.0;       // area of the map's free space (as published, no credit)
  double reachable_m2 = 0.0;      // area of the reachable free space
  double mapped_reachable_m2 = 0.0;  // area(map ∩ reachable), with the credit if any
  double coverage = 0.0;          // mapped_reachable / reachable (NaN: see coverage())
  double iou = 0.0;               // mapped_reachable / area(map ∪ reachable), with the credit if any
  double obstacle_on_wall = 0.0;  // see obstacle_on_wall(); NaN without obstacle edges
};
MapScore score_map(const mapping::TypedMultiPolygon& map, const geometry::Pose2& map_in_world,
                   const mapping::MultiPolygon& reachable, const WallIndex& walls, double wall_tolerance_m,
                   double obstacle_band_credit_m = 0.0, CreditNear credit_near = CreditNear::kMapObstacleEdges);

}  // namespace pex::evaluation
