#pragma once
// One laser scan -> the typed polygon of the free space it saw (paper,
// section "Polygonal domain"): Successive Edge Following splits the returns
// into clusters, Ramer-Douglas-Peucker reduces each cluster to a polyline, a
// least-squares line fit refines every polyline segment from its points and
// adjacent fitted lines are intersected for the vertices; the sensor origin is
// added and the pieces are joined into one simple polygon.
//
// Edges along clusters are obstacle; every other edge (joins between
// clusters, the two rays to the origin, arcs at the free range where beams had
// no return) is frontier.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>

#include "geometry/pose2.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

struct ScanPolygonOptions {
  // Readings that are NaN, inf, below range_min_m or at/beyond range_max_m
  // are "no return". The caller passes the tighter of its config and the
  // sensor's own limits.
  double range_min_m = 0.05;
  double range_max_m = 30.0;
  // A beam with no return marks free space up to this range (frontier arc).
  double free_range_m = 4.0;
  // Returns at or beyond this range give no obstacle edge; their beams mark
  // free space up to this range (frontier arc there). For a pose whose
  // heading is less certain than the far walls need: a heading error moves a
  // return sideways by range x error. 0: every return below range_max_m is
  // an obstacle (the paper's polygon). docs/mapping.md has what it measured.
  double obstacle_range_m = 0.0;
  // Every return is taken this much nearer the sensor along its beam. The
  // map is a union of scans, so at every wall it keeps the farthest of all
  // the noisy returns ever seen there: with the LMS1xx's ~12 mm range noise
  // that envelope lies 3-4 cm beyond the wall after a few hundred scans
  // (docs/mapping.md). Free space that ends a couple of sigma short of each
  // return puts the envelope back on the wall. 0: the returns as measured.
  double return_margin_m = 0.0;
  // Successive Edge Following with the adaptive breakpoint of Borges & Aldon
  // (2004): beams i-1 and i belong to one cluster when their points are at
  // most r[i-1] * sin(dphi) / sin(lambda - dphi) + 3 sigma apart, so the
  // break distance grows with the range.
  double break_lambda_rad = 10.0 * std::numbers::pi / 180.0;
  double break_sigma_m = 0.01;
  // ... and never more than this apart (0: no cap). The adaptive distance
  // grows with range and with a wall seen at a slant: 0.9 m at 16 m, so a
  // wall seen along its length from afar, with no beam through a door in it,
  // was drawn across the door, and the door's obstacle band closed it in the
  // planning map for good (docs/mapping.md, "Doors seen at a slant"). A gap
  // narrower than the robot closes nothing it could pass. Off in the shipped
  // config: the walls it dots with frontier made missions longer (same place).
  double break_max_gap_m = 0.0;
  // RDP tolerance for cluster polylines.
  double rdp_epsilon_m = 0.03;
  // Merge step after RDP: a vertex is dropped while the returns of its two
  // segments fit one line with an RMS residual of at most merge_max_rms_m
  // (0 = off). Range noise makes RDP split a straight wall at single noisy
  // returns into short edges across the wall; at a wall's end (a door jamb)
  // their obstacle band reached obstacle_outer_m into the doorway.
  double merge_max_rms_m = 0.02;
  // ... and no return lies farther than this from the merged line, which keeps
  // real corners whose short arm barely moves the RMS. 0.06 m is 5 sigma of the
  // LMS1xx's ~12 mm range noise: noise alone almost never exceeds it.
  double merge_max_deviation_m = 0.06;
  // Least-squares refit of each RDP segment; a vertex from intersecting two
  // fitted lines that moves farther than refit_max_shift_m from its RDP point
  // (nearly parallel lines) keeps the RDP point instead.
  bool least_squares_refit = true;
  double refit_max_shift_m = 0.10;
  // No-return arcs are sampled with at most this angle between vertices.
  double free_arc_step_rad = 0.1;
  // Scans with more beams are refused (bad input, not a 2D lidar).
  int max_beams = 100000;
  // Scans with fewer returns (is_return) are refused: a laser covered,
  // dazzled or gone blind answers "no echo" on every beam, and a beam
  // without a return is free space for free_range_m, through whatever wall
  // stands there. The shipped worlds' scans have 24 returns at the fewest
  // (campus, open ground), 371 indoors. 0: off.
  int min_returns = 0;
  // A beam without a return ends where it runs into a wall the map already
  // holds (known_walls.hpp): a laser blind in one sector (part of the window
  // covered, a cable in front of it) would otherwise carve the walls there
  // away. Read by the callers that have a map (the mapper, SLAM's particle
  // maps); scan_to_polygon takes the extents they give it.
  bool no_return_stops_at_walls = true;
};

// A beam's reading is a return: finite, at least range_min_m and below
// range_max_m (NaN, inf, 0 = no echo, out of range: no return).
inline bool is_return(double r, double range_min_m, double range_max_m) {
  return std::isfinite(r) && r >= range_min_m && r < range_max_m;
}

// How many of `ranges` are returns.
int count_returns(std::span<const float> ranges, double range_min_m, double range_max_m);

struct ScanPolygonResult {
  bool ok = false;
  std::string error;       // why there is no polygon, when !ok
  TypedPolygon polygon;    // valid, simple, counter-clockwise, no holes, when ok
  int beams_returned = 0;       // returns that drew obstacle edges
  int beams_no_return = 0;
  int beams_beyond_obstacle_range = 0;  // returns at or beyond obstacle_range_m
  int clusters = 0;
  // Which construction gave the polygon: 0 full (RDP + refit), 1 RDP without
  // refit, 2 every return as a vertex (always simple: a star around the origin).
  int fallback_level = 0;
};

// The free-space polygon of one scan. Beam i points at angle_min +
// i * angle_increment in the sensor frame; `sensor_pose` is the sensor's pose
// in the map frame. Never throws; bad input gives ok == false and an error.
// `no_return_extent_m`, when not empty (one value per beam of `ranges`, as
// no_return_extents in known_walls.hpp gives them): a beam without a return
// marks free space only that far (at most free_range_m), its own vertex
// where that is short of free_range_m, in place of the arc.
ScanPolygonResult scan_to_polygon(std::span<const float> ranges, double angle_min,
                                  double angle_increment, const geometry::Pose2& sensor_pose,
                                  const ScanPolygonOptions& options,
                                  std::span<const float> no_return_extent_m = {});

}  // namespace pex::mapping
