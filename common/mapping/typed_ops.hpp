#pragma once
// Boolean operations and offsetting on typed polygons. Union, difference and
// clip run our edge overlay (edge_overlay.hpp), which carries each edge's
// type; offsetting runs Boost.Geometry's buffer (the simpler tool there) and
// types its output with the reassignment pass (edge_reassignment.hpp).
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "mapping/edge_overlay.hpp"
#include "mapping/edge_reassignment.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

struct TypedOpOptions {
  // false: plain geometry, every edge typed frontier (the benchmark baseline).
  bool assign_edge_types = true;
  // Output edges lying on this box's boundary are typed kBorder without a
  // search (PolygonMap's tiles); nullopt: no such box.
  std::optional<Box> border_box;
  // Set: every non-border edge gets this type without a search (inputs whose
  // origin alone decides the type, such as the obstacle band).
  std::optional<EdgeType> uniform_type;
  // Check the output with bg::is_valid (ok == false if invalid); typed_union
  // checks its whole result, with the polygons it copied unchanged and the
  // holes it put back (the overlay moves its output onto its grid but not
  // the copies, so an edge can come to overlap a copy, and Boost's verdict
  // depends on the box it checks). PolygonMap turns it off for intermediate
  // results and checks each tile once at the end of an insert instead
  // (validity checks cost as much as the overlay); the explorer's live view
  // turns it off (planning only: live_view.cpp).
  bool validate = true;
  // true: typed_union, typed_clip and typed_difference use Boost.Geometry's
  // overlay and the reassignment pass instead of the edge overlay (the
  // oracle of tests and fuzzing, the benchmark's comparison). Never a
  // fallback: when the edge overlay fails, the operation fails.
  bool boost_overlay = false;
};

struct TypedOpResult {
  bool ok = false;
  std::string error;          // why not ok: the overlay failed, or the output is invalid
  TypedMultiPolygon polygons;
  ReassignStats reassign;
  // typed_union only: the last `unchanged_tail` polygons are polygons of `a`
  // that took no part (their boxes meet no polygon of b), returned as they
  // were, so a caller that knew them valid need not check them again.
  std::size_t unchanged_tail = 0;
};

// Union of a and b; each output edge keeps the type of its source edge.
// Both must be valid (interior-disjoint polygons). Only polygons whose boxes
// meet a polygon of the other side go through the overlay; the others are
// disjoint from everything and are copied (b's after the overlay's output,
// a's at the end: see unchanged_tail).
TypedOpResult typed_union(const TypedMultiPolygon& a, const TypedMultiPolygon& b,
                          const TypedOpOptions& options = {});

// a minus b. Edges from a take `a_type` (their own type if nullopt), edges
// from b take `b_type` (their own if nullopt); where an edge of a and one of b
// coincide, the more specific type. The paper's planning map is
// typed_difference(free, obstacles, kFrontier, kObstacle).
TypedOpResult typed_difference(const TypedMultiPolygon& a, const TypedMultiPolygon& b,
                               std::optional<EdgeType> a_type, std::optional<EdgeType> b_type,
                               const TypedOpOptions& options = {});

// Intersection of a typed polygon with a box: edges on the box's boundary are
// kBorder, the others keep the polygon's types.
TypedOpResult typed_clip(const TypedMultiPolygon& polygons, const Box& box,
                         const TypedOpOptions& options = {});

// Minkowski offset by distance_m (> 0 grows, < 0 shrinks), round joins with
// `points_per_circle`. For a disk robot of radius r the configuration free
// space is typed_offset(free_space, -r): each output edge takes the type of
// the input edge it was offset from.
TypedOpResult typed_offset(const TypedMultiPolygon& polygons, double distance_m,
                           int points_per_circle = 16, const TypedOpOptions& options = {});

// Whether an overlay's result area `got` lies in [lo, hi], the bounds any
// correct result keeps, up to what the overlay's rounding onto its grid can
// move an area: kOverlayMovesM times the operands' boundary length, which
// boundary_m() measures (called only when the plain test fails).
template <class BoundaryLength>
bool area_within(double got, double lo, double hi, BoundaryLength&& boundary_m) {
  const double plain = 1e-9 * std::max({1.0, std::abs(lo), std::abs(hi)});
  if (got >= lo - plain && got <= hi + plain) return true;
  const double moved = plain + boundary_m() * kOverlayMovesM;
  return got >= lo - moved && got <= hi + moved;
}

// Types `geometry` from `index` (or all frontier when !assign_edge_types),
// with border edges of options.border_box typed kBorder.
TypedMultiPolygon assign_types(const MultiPolygon& geometry, const EdgeTypeIndex& index,
                               double search_radius_m, const TypedOpOptions& options,
                               ReassignStats* stats);

// A hole taken out of its polygon while the polygon goes through an overlay
// that cannot reach it (typed_union, PolygonMap's merge), with its edge types.
struct TypedRing {
  Ring ring;
  std::vector<EdgeType> types;
};

// Clears set_aside[k] (hole k of `polygon` to be left out of an overlay) for
// every hole that comes within clearance_m of a ring that goes through it:
// the outer ring, the holes not set aside and, in turn, the holes cleared
// here. The overlay moves those rings by up to kOverlayMovesM, and a hole
// left out beside one (valid rings may touch at a point) could then overlap
// it: the hole would not go back (office, START turned 90 degrees: the free
// space merge refused the map).
void keep_holes_near_overlaid_rings(const TypedPolygon& polygon, std::vector<char>& set_aside, double clearance_m);

// The polygon without the holes for which set_aside(ring) is true and that
// keep clear of the rings that stay (keep_holes_near_overlaid_rings, by twice
// kOverlayMovesM); those are appended to `aside` with their types (to go back
// with put_back_holes).
template <class Pred>
TypedPolygon without_holes(const TypedPolygon& polygon, Pred&& set_aside, std::vector<TypedRing>& aside) {
  const auto& holes = polygon.geometry.inners();
  std::vector<char> leave_out(holes.size());
  bool any = false;
  for (std::size_t k = 0; k < holes.size(); ++k) any = (leave_out[k] = set_aside(holes[k]) ? 1 : 0) || any;
  if (any) keep_holes_near_overlaid_rings(polygon, leave_out, 2.0 * kOverlayMovesM);
  TypedPolygon kept{Polygon{}, {polygon.edge_types[0]}};
  kept.geometry.outer() = polygon.geometry.outer();
  for (std::size_t k = 0; k < holes.size(); ++k) {
    if (leave_out[k]) {
      aside.push_back({holes[k], polygon.edge_types[1 + k]});
    } else {
      kept.geometry.inners().push_back(holes[k]);
      kept.edge_types.push_back(polygon.edge_types[1 + k]);
    }
  }
  return kept;
}

// Puts each hole back into the polygon that contains it: the smallest one
// whose outer ring covers a point just inside the hole (left of its first
// edge; holes run clockwise). Outer rings are nested or disjoint, so the
// smallest is the innermost. False (polygons unchanged from that hole on) if
// a hole has no such polygon or is degenerate.
bool put_back_holes(TypedMultiPolygon& polygons, std::vector<TypedRing> holes);

// True if edge a-b lies on one side of the box (both ends exactly on the same
// side line): a tile's border edge, typed kBorder.
bool on_same_box_side(const Point& a, const Point& b, const Box& box);

// Sets coordinates within 1e-9 m of the box's sides exactly onto them, so
// neighbouring tiles share bit-identical border vertices.
void snap_to_box(MultiPolygon& geometry, const Box& box);

}  // namespace pex::mapping
