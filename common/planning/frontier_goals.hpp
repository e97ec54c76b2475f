#pragma once
// Goal candidates on the frontiers of a typed polygonal map (paper, section
// "Map representation"): candidates lie on frontier edges, neighbours about
// twice the sensor range apart along the frontier, so that every frontier
// point is within sensor range of some candidate; visiting all candidates
// therefore reveals what lies behind every frontier.
#include <cstddef>
#include <limits>
#include <vector>

#include "mapping/typed_polygon.hpp"

namespace pex::planning {

using mapping::Point;
using mapping::TypedMultiPolygon;

// A maximal run of consecutive frontier edges of one ring.
struct FrontierChain {
  std::vector<Point> points;  // polyline; closed chains repeat the first point at the end
  bool closed = false;        // the whole ring is frontier
  double length_m = 0.0;
  // The area of the unknown region the chain borders, when the map encloses
  // it: the chain lies on a hole of a map polygon (or on the outer ring of a
  // polygon inside such a hole), and the region is the hole less the map's
  // polygons inside it. +inf when the chain borders the unbounded outside.
  // Everything in a hole is obstacle or unseen, so no visit to the chain can
  // reveal more than this: the shadow behind a desk seen from three sides,
  // the inside of a cabinet seen through a crack, a pillar's unseen face.
  double enclosed_area_m2 = std::numeric_limits<double>::infinity();
  // The area of the walled bay the chain lies in (find_walled_bays), +inf
  // when none was looked for or found.
  double bay_area_m2 = std::numeric_limits<double>::infinity();
  // The smaller of the two: what a visit to the chain can reveal at most.
  double enclosed_or_bay_area_m2() const { return enclosed_area_m2 < bay_area_m2 ? enclosed_area_m2 : bay_area_m2; }
  // Where the chain lies: map polygon, ring (0 outer, 1 + k the k-th hole)
  // and its first edge (ring[first_edge] -> ring[first_edge + 1]) and edge
  // count; a closed chain is the whole ring.
  int polygon = -1, ring = -1;
  std::size_t first_edge = 0, edge_count = 0;
};

// Every frontier chain of the map, ring by ring in map order, each with the
// area it encloses (FrontierChain::enclosed_area_m2). Edges typed kBorder (a
// tile border that was not dissolved) count as frontier: they separate the
// map from space it does not describe.
// `polygons_not_placed` as for enclosed_areas.
std::vector<FrontierChain> frontier_chains(const TypedMultiPolygon& map, int* polygons_not_placed = nullptr);

// Per polygon of `map`, per ring (outer first, then the holes, as
// TypedPolygon::edge_types): the area of the unknown region the ring borders
// on its non-free side, +inf for an outer ring not inside any hole. A hole's
// region is the hole less the outer rings of the polygons directly inside it
// (polygons are interior-disjoint, so each lies wholly in a hole or outside
// it); an outer ring inside a hole borders that hole's region (the innermost
// hole holding it).
// Finding the hole that holds a polygon reads the ring of each hole whose
// box covers it, within a budget of kEnclosedLookupVerticesPerMapVertex
// ring vertices per map vertex (plus kEnclosedLookupVerticesFloor): past
// it, a polygon is not placed (counted in `polygons_not_placed` if given),
// and its outer ring and the holes it was to be tested against border
// unbounded regions, so frontiers are never wrongly taken as enclosed.
inline constexpr std::size_t kEnclosedLookupVerticesPerMapVertex = 64;
inline constexpr std::size_t kEnclosedLookupVerticesFloor = 1'000'000;
std::vector<std::vector<double>> enclosed_areas(const TypedMultiPolygon& map, int* polygons_not_placed = nullptr);

// A walled bay: a notch of a map ring on its unknown side that a straight
// lid closes, the lid continuing a wall on both sides, with an obstacle face
// standing in front of the lid. It is what a desk, a cabinet or a box
// against a wall leaves: the laser saw the object's front and the wall on
// both sides, not the object's flank nor the wall behind it; the frontier
// on the flank borders a region the map all but encloses, which a look
// from the flank shows to be the object and a strip of wall. Bays of more
// than max_area_m2 are not looked for: a room seen through a door has its
// door's jambs in line, but its unknown region is larger, and the lid across
// a door the laser saw through crosses the free space.
struct WalledBayOptions {
  double max_area_m2 = 0.0;  // 0: off
  // The lid: the stretch of wall nobody saw, from the end of a wall edge
  // before the chain to the start of one after it (each at least min_wall_m
  // long and turned no more than max_lid_turn_rad from the lid, or one of
  // them a room's corner: max_corner_turn_rad), at most max_lid_m long.
  // Straight only: a lid round a corner would close a room's worth of
  // unknown seen through a door as readily as the corner behind a desk.
  double max_lid_m = 3.0;
  double min_wall_m = 0.1;
  double max_lid_turn_rad = 0.2;
  // In a room's corner the lid continues one wall only, up to the other
  // (the side wall) where it meets the first one's line: a desk in the
  // corner hides the far wall to the corner. The side wall turns off the
  // lid's line into the room by a right angle, give or take this; its end
  // lies within max_beyond_lid_m of that line. The lid still turns no
  // corner: it is straight, along a wall.
  double max_corner_turn_rad = 0.35;
  // An obstacle edge of the bay (at least min_wall_m long) whose middle is
  // this far from the lid: the object in front of the unseen wall. Without one
  // the notch is the wall itself, seen at a grazing angle or not at all,
  // where a door may be.
  double min_depth_m = 0.2;
  // How far along the ring, on each side of the chain, the lid's ends are
  // looked for.
  double search_m = 8.0;
  // The lid crosses no edge of the map but within this of its ends (at most
  // a quarter of its length): there the ragged steps of a wall's obstacle
  // band, where it meets the frontier, cross the wall's line.
  double lid_end_tolerance_m = 0.05;
  // The bay's own ring, from wall to wall, goes no further than this beyond
  // the lid's line (the band's steps, and a flank's frontier ending below
  // the line), and may cross the lid where it does, anywhere along it: a
  // flank's step 6 cm from the lid's end kept a desk a goal (floor120 at
  // 605 m of travel, 4 of its 5 desk flanks at the far walls). A door the
  // laser saw through puts the ring metres beyond the lid.
  double max_beyond_lid_m = 0.10;
  // Nor an edge of a map polygon smaller than this: a sliver of free space
  // seen past the object's end into the strip behind it lies in the bay.
  // A room seen through a gap behind the object is larger, and stops it.
  double min_piece_m2 = 0.25;
};

// Sets bay_area_m2 of every chain that lies in a walled bay of less than
// options.max_area_m2 (the smallest such bay). `chains` as frontier_chains
// gave them for `map`. The ring steps read have a budget of
// kWalledBayStepsPerMapVertex per map vertex plus kWalledBayStepsFloor;
// past it the chains left keep bay_area_m2 +inf (goals, as without bays).
inline constexpr std::size_t kWalledBayStepsPerMapVertex = 64;
inline constexpr std::size_t kWalledBayStepsFloor = 1'000'000;
void find_walled_bays(const TypedMultiPolygon& map, std::vector<FrontierChain>& chains,
                      const WalledBayOptions& options);

struct FrontierGoalOptions {
  // Radius within which a candidate "covers" the frontier (the paper's sensor
  // range; an effective range below the laser's maximum gives denser goals).
  double sensor_range_m = 5.0;
  // Chains shorter than this are noise (gaps between scan points, slivers
  // along walls) and get no candidate.
  double min_frontier_length_m = 0.3;
};

struct FrontierPoint {
  Point point;               // on the chain
  int chain = -1;            // index into the chains
  double chain_length_m = 0.0;
  // The arc of the chain this candidate covers, [arc_from_m, arc_to_m] in
  // arc length from the chain's first point; `point` is its middle.
  double arc_from_m = 0.0, arc_to_m = 0.0;
};

// Candidates on the chains: a chain of length L >= min_frontier_length_m gets
// n = ceil(L / (2 * sensor_range_m)) candidates at arc lengths (i + 1/2) L / n,
// so each covers the arc of length L / n around it and, because a chord is no
// longer than its arc, every point of the chain is within sensor_range_m of
// a candidate. `dropped_chains`, if given, counts the chains too short.
std::vector<FrontierPoint> frontier_candidates(const std::vector<FrontierChain>& chains,
                                               const FrontierGoalOptions& options,
                                               int* dropped_chains = nullptr);

// The point at arc length s along a polyline (clamped to its ends).
Point point_at_arc_length(const std::vector<Point>& polyline, double s);

}  // namespace pex::planning
