#pragma once
// Test support (not used by the library): small typed maps written by hand.
#include <cmath>
#include <vector>

#include "mapping/typed_polygon.hpp"
#include "planning/cspace.hpp"
#include "planning/exploration_planner.hpp"

namespace pex::planning::testing {

using mapping::EdgeType;
using mapping::Point;

// A ring from distinct vertices (closed here), with one type per edge.
struct RingSpec {
  std::vector<Point> points;
  std::vector<EdgeType> types;  // empty: all obstacle
};

inline mapping::Ring closed_ring(const std::vector<Point>& points) {
  mapping::Ring ring(points.begin(), points.end());
  ring.push_back(points.front());
  return ring;
}

// A typed polygon; the outer ring must be counter-clockwise, holes clockwise.
inline mapping::TypedPolygon typed_polygon(const RingSpec& outer, const std::vector<RingSpec>& holes = {}) {
  mapping::TypedPolygon p;
  p.geometry.outer() = closed_ring(outer.points);
  auto types_of = [](const RingSpec& r) {
    return r.types.empty() ? std::vector<EdgeType>(r.points.size(), EdgeType::kObstacle) : r.types;
  };
  p.edge_types.push_back(types_of(outer));
  for (const auto& h : holes) {
    p.geometry.inners().push_back(closed_ring(h.points));
    p.edge_types.push_back(types_of(h));
  }
  return p;
}

// Axis-aligned rectangle, counter-clockwise from (x0, y0); types per side in
// the order bottom, right, top, left.
inline RingSpec rectangle(double x0, double y0, double x1, double y1,
                          std::vector<EdgeType> types = {}) {
  return RingSpec{{Point(x0, y0), Point(x1, y0), Point(x1, y1), Point(x0, y1)}, std::move(types)};
}

// The same rectangle clockwise (a hole), from (x0, y0) up the left side.
inline RingSpec rectangle_hole(double x0, double y0, double x1, double y1) {
  return RingSpec{{Point(x0, y0), Point(x0, y1), Point(x1, y1), Point(x1, y0)}, {}};
}

// Distance from p to the boundary of a ring.
inline double distance_to_ring(const Point& p, const std::vector<Point>& ring) {
  double best = 1e300;
  for (std::size_t i = 0; i < ring.size(); ++i)
    best = std::min(best, distance(p, closest_point_on_segment(p, ring[i], ring[(i + 1) % ring.size()])));
  return best;
}

// Where a path (a polyline) first crosses the line x = `x` (NaN: it does not):
// through a door or through the glass beside it.
inline double crossing_y(const std::vector<Point>& path, double x) {
  for (std::size_t k = 1; k < path.size(); ++k) {
    const auto& a = path[k - 1];
    const auto& b = path[k];
    if ((a.x() - x) * (b.x() - x) <= 0.0 && a.x() != b.x()) return a.y() + (b.y() - a.y()) * (x - a.x()) / (b.x() - a.x());
  }
  return std::nan("");
}

// C-space options of a bare disk robot: no margin, no simplification.
inline CSpaceOptions disk(double radius_m) {
  CSpaceOptions o;
  o.robot_radius_m = radius_m;
  o.clearance_margin_m = 0.0;
  o.simplify_epsilon_m = 0.0;
  return o;
}

// The planner of the door and glass tests: a 0.27 m robot with a 5 cm
// margin, a frontier's goal at the frontier itself (no look from afar).
inline PlannerOptions door_planner_options() {
  PlannerOptions o;
  o.cspace.robot_radius_m = 0.27;
  o.cspace.clearance_margin_m = 0.05;
  o.approach_range_m = 0.0;
  return o;
}

// A room 10 x 4 m with a pillar, and through a slit 0.3 m wide (narrower
// than the robot) at its east wall a second room whose far wall (x = 16) is
// frontier: that room's C-space is a piece of its own. The far wall is in
// view through the slit, so with approach points on (approach_range_m) it
// gets one in the first room; with them off its candidate has no path.
inline mapping::TypedMultiPolygon a_room_cut_off_behind_a_slit() {
  constexpr auto O = EdgeType::kObstacle;
  auto map = typed_polygon(RingSpec{{Point(0, 0), Point(10, 0), Point(10, 1.85), Point(11, 1.85), Point(11, 0),
                                     Point(16, 0), Point(16, 4), Point(11, 4), Point(11, 2.15), Point(10, 2.15),
                                     Point(10, 4), Point(0, 4)},
                                    {O, O, O, O, O, EdgeType::kFrontier, O, O, O, O, O, O}},
                           {rectangle_hole(4, 1.5, 5, 2.5)});
  return {map};
}

// A room from x = west_x to 10, 4 m deep, and, through a gap `gap_m` wide in
// its 1 m thick east wall (centred at y = 2), a second room 11 x 4 m (x = 11
// to 22); the first room's west wall and the second's east wall are of the
// types given. Each wall is farther than approach_range_m's 8 m from the
// other room when west_x <= 0.
inline mapping::TypedMultiPolygon a_room_behind_a_gap(double gap_m, double west_x, EdgeType west_wall,
                                                      EdgeType east_wall) {
  constexpr auto O = EdgeType::kObstacle;
  const double lo = 2.0 - gap_m / 2, hi = 2.0 + gap_m / 2;
  return {typed_polygon(RingSpec{{Point(west_x, 0), Point(10, 0), Point(10, lo), Point(11, lo), Point(11, 0),
                                  Point(22, 0), Point(22, 4), Point(11, 4), Point(11, hi), Point(10, hi), Point(10, 4),
                                  Point(west_x, 4)},
                                 {O, O, O, O, O, east_wall, O, O, O, O, O, west_wall}})};
}

// The room of a_room_behind_a_gap (hall from x = -10) with its east wall
// seen, and a slot 0.42 m wide and 2 m deep in its north wall (x = 16..16.42,
// y = 4..6) whose end is frontier: more than the snap distance from the
// room's C-space, in view from it straight up the slot, and from nowhere in
// the hall (the gap is 1 m long).
inline mapping::TypedMultiPolygon a_slot_in_a_room_behind_a_gap(double gap_m) {
  constexpr auto O = EdgeType::kObstacle;
  constexpr auto F = EdgeType::kFrontier;
  const double lo = 2.0 - gap_m / 2, hi = 2.0 + gap_m / 2;
  return {typed_polygon(RingSpec{{Point(-10, 0), Point(10, 0), Point(10, lo), Point(11, lo), Point(11, 0),
                                  Point(22, 0), Point(22, 4), Point(16.42, 4), Point(16.42, 6), Point(16, 6),
                                  Point(16, 4), Point(11, 4), Point(11, hi), Point(10, hi), Point(10, 4),
                                  Point(-10, 4)},
                                 {O, O, O, O, O, O, O, O, F, O, O, O, O, O, O, O}})};
}

// A 200 x 200 m room with a round hole of `hole_vertices` (radius 95 m
// about (100, 100)) holding `islands` squares, 0.3 of their grid pitch
// across, on a square grid over (40..160, 40..160): many polygons in one
// long hole, as a hostile MAP would have them (enclosed_areas' work budget).
inline mapping::TypedMultiPolygon islands_in_a_long_hole(int hole_vertices, int islands) {
  RingSpec hole;
  for (int k = 0; k < hole_vertices; ++k) {  // clockwise
    const double a = -2.0 * M_PI * k / hole_vertices;
    hole.points.emplace_back(100.0 + 95.0 * std::cos(a), 100.0 + 95.0 * std::sin(a));
  }
  mapping::TypedMultiPolygon map{typed_polygon(rectangle(0, 0, 200, 200), {hole})};
  const int per_row = static_cast<int>(std::ceil(std::sqrt(islands)));
  const double pitch = 120.0 / per_row;
  for (int i = 0; i < islands; ++i) {
    const double x = 40.0 + pitch * (i % per_row), y = 40.0 + pitch * (i / per_row);
    map.push_back(typed_polygon(rectangle(x, y, x + 0.3 * pitch, y + 0.3 * pitch)));
  }
  return map;
}

}  // namespace pex::planning::testing
