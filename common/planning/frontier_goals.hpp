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
