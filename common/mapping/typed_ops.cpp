// Boost.Geometry 1.74 buffer/rescale code trips -Wmaybe-uninitialized when
// inlined into our code; the warning is in Boost, not here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "mapping/typed_ops.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

namespace pex::mapping {

namespace {

constexpr double kSnap = 1e-9;
constexpr double kClipSearchRadius = 1e-6;

TypedOpResult finish(MultiPolygon geometry, const EdgeTypeIndex& index, double search_radius_m,
                     const TypedOpOptions& options) {
  TypedOpResult result;
  if (options.border_box) snap_to_box(geometry, *options.border_box);
  std::string why;
  if (options.validate && !bg::is_valid(geometry, why)) {
    result.error = "invalid result: " + why;
    return result;
  }
  result.polygons = assign_types(geometry, index, search_radius_m, options, &result.reassign);
  result.ok = true;
  return result;
}

// The polygons whose rings are rings[starts[k]] .. rings[starts[k + 1] - 1]
// (outer ring first), copied.
TypedMultiPolygon copy_polygons(const std::vector<RingRef>& rings, const std::vector<std::size_t>& starts) {
  TypedMultiPolygon polygons;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const std::size_t end = k + 1 < starts.size() ? starts[k + 1] : rings.size();
    TypedPolygon polygon;
    polygon.geometry.outer() = *rings[starts[k]].ring;
    polygon.edge_types.push_back(*rings[starts[k]].types);
    for (std::size_t r = starts[k] + 1; r < end; ++r) {
      polygon.geometry.inners().push_back(*rings[r].ring);
      polygon.edge_types.push_back(*rings[r].types);
    }
    polygons.push_back(std::move(polygon));
  }
  return polygons;
}

TypedOpResult failed(std::string why) {
  TypedOpResult result;
  result.error = std::move(why);
  return result;
}

// Net area of rings as the overlay takes them: outer rings counter-clockwise
// (positive to Boost's area for our ring type), holes clockwise (negative).
double net_area(std::span<const RingRef> rings) {
  double sum = 0.0;
  for (const RingRef& r : rings) sum += bg::area(*r.ring);
  return sum;
}

// The bounds any correct result's area keeps (union: each operand and no more
// than both; difference: a less b and no more than a; intersection: no more
// than either), with room for our overlay's rounding (area_within) if
// `rounded`, else (Boost's overlay, which does not round onto a grid) for
// 1e-6 of the area. Why: on degenerate
// operands (slivers of 1e-10 m², vertices repeated 1e-9 m apart: the fuzzer's
// fuzz/corpus/typed_ops/regression_*)
// the overlay can return ok with a hole filled or an operand lost; a map
// built on that is wrong for good, a refused operation is counted and the
// caller keeps what it had.
std::optional<std::string> area_out_of_bounds(std::span<const RingRef> a, std::span<const RingRef> b, OverlayOp op,
                                              const TypedMultiPolygon& out, bool rounded) {
  const double area_a = net_area(a), area_b = net_area(b);
  double lo = 0.0, hi = 0.0;
  switch (op) {
    case OverlayOp::kUnion: lo = std::max(area_a, area_b), hi = area_a + area_b; break;
    case OverlayOp::kDifference: lo = std::max(0.0, area_a - area_b), hi = area_a; break;
    case OverlayOp::kIntersection: lo = 0.0, hi = std::min(area_a, area_b); break;
  }
  const double got = area(out);
  auto boundary_m = [&] {
    double length = 0.0;
    for (const auto* side : {&a, &b})
      for (const RingRef& r : *side) length += bg::perimeter(*r.ring);
    return length;
  };
  const double relative = 1e-6 * std::max(1.0, hi);
  if (rounded ? area_within(got, lo, hi, boundary_m) : got >= lo - relative && got <= hi + relative)
    return std::nullopt;
  return "overlay result of " + std::to_string(got) + " m2 outside [" + std::to_string(lo) + ", " +
         std::to_string(hi) + "] m2 (degenerate operands)";
}

// Boost's overlay (TypedOpOptions::boost_overlay) is held to the same area
// bounds: on valid operands its union can come back empty (the typed_ops
// fuzzer, 2026-11-26: a union of 0 m2 of operands of 4 and 3.75 m2).
void refuse_out_of_bounds(std::span<const RingRef> a, std::span<const RingRef> b, OverlayOp op,
                          TypedOpResult& result) {
  if (!result.ok) return;
  if (auto bad_area = area_out_of_bounds(a, b, op, result.polygons, false)) {
    result.ok = false;
    result.error = "Boost's overlay: " + *bad_area;
    result.polygons.clear();
  }
}

// Our edge overlay (edge_overlay.hpp): `result` filled (ok, or the error),
// its output retyped as assign_types would type it when the options ask for
// uniform or plain types, checked against the area bounds always and for
// validity if options.validate.
void edge_overlay(std::span<const RingRef> a, std::span<const RingRef> b, OverlayOp op,
                  const TypedOpOptions& options, TypedOpResult& result,
                  const std::optional<EdgeType> (&side_types)[2] = {}) {
  OverlayResult r = overlay(a, b, op, options.border_box, side_types);
  std::string why;
  if (r.ok) {
    if (auto bad_area = area_out_of_bounds(a, b, op, r.polygons, true)) {
      r.ok = false;
      r.error = std::move(*bad_area);
    }
  }
  if (r.ok && options.validate && !is_valid_cheap_first(r.polygons, why)) {
    r.ok = false;
    r.error = "invalid result: " + why;
  }
  if (!r.ok) {
    result.ok = false;
    result.error = std::move(r.error);
    return;
  }
  if (!options.assign_edge_types || options.uniform_type) {  // as assign_types types them
    const EdgeType plain = options.uniform_type.value_or(EdgeType::kFrontier);
    auto retype = [&](const Ring& ring, std::vector<EdgeType>& types) {
      for (std::size_t i = 0; i + 1 < ring.size(); ++i)
        types[i] = options.border_box && on_same_box_side(ring[i], ring[i + 1], *options.border_box)
                       ? EdgeType::kBorder
                       : plain;
    };
    for (auto& polygon : r.polygons) {
      retype(polygon.geometry.outer(), polygon.edge_types[0]);
      for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
        retype(polygon.geometry.inners()[k], polygon.edge_types[1 + k]);
    }
  }
  result.polygons = std::move(r.polygons);
  result.ok = true;
}

}  // namespace

bool on_same_box_side(const Point& a, const Point& b, const Box& box) {
  const auto& lo = box.min_corner();
  const auto& hi = box.max_corner();
  return (a.x() == lo.x() && b.x() == lo.x()) || (a.x() == hi.x() && b.x() == hi.x()) ||
         (a.y() == lo.y() && b.y() == lo.y()) || (a.y() == hi.y() && b.y() == hi.y());
}

void snap_to_box(MultiPolygon& geometry, const Box& box) {
  const double xs[2] = {box.min_corner().x(), box.max_corner().x()};
  const double ys[2] = {box.min_corner().y(), box.max_corner().y()};
  auto snap_ring = [&](Ring& ring) {
    for (auto& p : ring) {
      for (double x : xs)
        if (std::abs(p.x() - x) <= kSnap) p.x(x);
      for (double y : ys)
        if (std::abs(p.y() - y) <= kSnap) p.y(y);
    }
  };
  for (auto& polygon : geometry) {
    snap_ring(polygon.outer());
    for (auto& inner : polygon.inners()) snap_ring(inner);
  }
}

TypedMultiPolygon assign_types(const MultiPolygon& geometry, const EdgeTypeIndex& index,
                               double search_radius_m, const TypedOpOptions& options,
                               ReassignStats* stats) {
  TypedMultiPolygon out;
  out.reserve(geometry.size());
  auto type_ring = [&](const Ring& ring) {
    std::vector<EdgeType> types;
    types.reserve(ring.empty() ? 0 : ring.size() - 1);
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
      if (options.border_box && on_same_box_side(ring[i], ring[i + 1], *options.border_box)) {
        types.push_back(EdgeType::kBorder);
        continue;
      }
      if (options.uniform_type || !options.assign_edge_types) {
        types.push_back(options.uniform_type.value_or(EdgeType::kFrontier));
        continue;
      }
      const auto m = index.match(ring[i], ring[i + 1], search_radius_m);
      types.push_back(m.type);
      if (stats) {
        ++stats->edges;
        stats->candidates += m.candidates;
      }
    }
    return types;
  };
  for (const auto& polygon : geometry) {
    TypedPolygon typed{polygon, {}};
    typed.edge_types.reserve(1 + polygon.inners().size());
    typed.edge_types.push_back(type_ring(polygon.outer()));
    for (const auto& inner : polygon.inners()) typed.edge_types.push_back(type_ring(inner));
    out.push_back(std::move(typed));
  }
  return out;
}

void keep_holes_near_overlaid_rings(const TypedPolygon& polygon, std::vector<char>& set_aside, double clearance_m) {
  // The edges of the rings that go through the overlay, with their boxes;
  // holes cleared are appended, so one pass per round tests the new ones.
  struct Edge {
    Point a, b;
    Box box;
  };
  std::vector<Edge> overlaid;
  auto add_ring = [&](const Ring& ring) {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
      Box box(ring[i], ring[i]);
      bg::expand(box, ring[i + 1]);
      overlaid.push_back({ring[i], ring[i + 1], box});
    }
  };
  const auto& holes = polygon.geometry.inners();
  add_ring(polygon.geometry.outer());
  std::vector<Box> near_box(holes.size());  // the hole's box grown by the clearance
  for (std::size_t k = 0; k < holes.size(); ++k) {
    if (!set_aside[k]) {
      add_ring(holes[k]);
      continue;
    }
    const Box box = bg::return_envelope<Box>(holes[k]);
    near_box[k] = Box(Point(box.min_corner().x() - clearance_m, box.min_corner().y() - clearance_m),
                      Point(box.max_corner().x() + clearance_m, box.max_corner().y() + clearance_m));
  }
  using EdgeSegment = bg::model::segment<Point>;
  auto near = [&](const Ring& hole, const Box& hole_near_box, const Edge& e) {
    if (bg::disjoint(hole_near_box, e.box)) return false;
    const EdgeSegment s(e.a, e.b);
    for (std::size_t i = 0; i + 1 < hole.size(); ++i)
      if (bg::distance(EdgeSegment(hole[i], hole[i + 1]), s) <= clearance_m) return true;
    return false;
  };
  for (std::size_t tested = 0; tested < overlaid.size();) {
    const std::size_t end = overlaid.size();
    for (std::size_t k = 0; k < holes.size(); ++k) {
      if (!set_aside[k]) continue;
      for (std::size_t i = tested; i < end; ++i)
        if (near(holes[k], near_box[k], overlaid[i])) {
          set_aside[k] = 0;
          add_ring(holes[k]);
          break;
        }
    }
    tested = end;
  }
}

bool put_back_holes(TypedMultiPolygon& polygons, std::vector<TypedRing> holes) {
  if (holes.empty()) return true;
  std::vector<Box> boxes;
  std::vector<double> areas;
  boxes.reserve(polygons.size());
  areas.reserve(polygons.size());
  for (const auto& p : polygons) {
    boxes.push_back(bg::return_envelope<Box>(p.geometry.outer()));
    areas.push_back(std::abs(bg::area(p.geometry.outer())));
  }
  std::vector<std::vector<Box>> hole_boxes(polygons.size());  // filled when first needed
  for (auto& hole : holes) {
    if (hole.ring.size() < 4) return false;
    std::size_t e = 0;  // the first edge of non-zero length
    while (e + 2 < hole.ring.size() && bg::equals(hole.ring[e], hole.ring[e + 1])) ++e;
    const Point& p0 = hole.ring[e];
    const Point& p1 = hole.ring[e + 1];
    const double dx = p1.x() - p0.x(), dy = p1.y() - p0.y(), len = std::hypot(dx, dy);
    if (len == 0.0) return false;
    const double step = std::min(1e-6, 0.25 * len) / len;
    const Point probe(0.5 * (p0.x() + p1.x()) - dy * step, 0.5 * (p0.y() + p1.y()) + dx * step);
    std::size_t home = polygons.size();
    for (std::size_t k = 0; k < polygons.size(); ++k) {
      if (!bg::covered_by(probe, boxes[k])) continue;
      if (home != polygons.size() && areas[k] >= areas[home]) continue;
      if (inside_ring(probe, polygons[k].geometry.outer())) home = k;
    }
    if (home == polygons.size()) return false;
    // Inside the innermost outer ring but in one of its holes: the hole
    // belongs to no polygon (its source was not in the union).
    auto& inners = polygons[home].geometry.inners();
    auto& boxes_of_inners = hole_boxes[home];
    while (boxes_of_inners.size() < inners.size())
      boxes_of_inners.push_back(bg::return_envelope<Box>(inners[boxes_of_inners.size()]));
    for (std::size_t k = 0; k < inners.size(); ++k)
      if (bg::covered_by(probe, boxes_of_inners[k]) && inside_ring(probe, inners[k])) return false;
    inners.push_back(std::move(hole.ring));
    polygons[home].edge_types.push_back(std::move(hole.types));
  }
  return true;
}

TypedOpResult typed_union(const TypedMultiPolygon& a, const TypedMultiPolygon& b,
                          const TypedOpOptions& options) {
  auto boxes_of = [](const TypedMultiPolygon& polygons) {
    std::vector<Box> boxes;
    boxes.reserve(polygons.size());
    for (const auto& p : polygons) boxes.push_back(bg::return_envelope<Box>(p.geometry));
    return boxes;
  };
  auto meets_any = [](const Box& box, const std::vector<Box>& boxes, const std::vector<char>* only) {
    for (std::size_t k = 0; k < boxes.size(); ++k)
      if ((!only || (*only)[k]) && !bg::disjoint(box, boxes[k])) return true;
    return false;
  };
  const std::vector<Box> a_boxes = boxes_of(a), b_boxes = boxes_of(b);
  std::vector<char> a_involved(a.size()), b_involved(b.size());
  for (std::size_t i = 0; i < a.size(); ++i) a_involved[i] = meets_any(a_boxes[i], b_boxes, nullptr);
  for (std::size_t j = 0; j < b.size(); ++j) b_involved[j] = meets_any(b_boxes[j], a_boxes, &a_involved);
  // Holes of a's polygons whose boxes meet no polygon of b stay holes of the
  // output polygon that contains them: they are set aside and put back after
  // the overlay, which then sees only the holes near b (in a map, most of a
  // tile's obstacles are far from a new scan).
  std::vector<TypedRing> aside;
  std::vector<RingRef> a_rings, b_rings;  // the overlay's operands, by reference
  std::vector<std::size_t> a_starts, b_starts;
  std::vector<Box> b_part_boxes;
  for (std::size_t j = 0; j < b.size(); ++j) {
    if (!b_involved[j]) continue;
    b_starts.push_back(b_rings.size());
    add_rings(b[j], b_rings);
    b_part_boxes.push_back(b_boxes[j]);
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a_involved[i]) continue;
    const TypedPolygon& polygon = a[i];
    a_starts.push_back(a_rings.size());
    a_rings.push_back({&polygon.geometry.outer(), &polygon.edge_types[0]});
    for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k) {
      const Ring& hole = polygon.geometry.inners()[k];
      if (meets_any(bg::return_envelope<Box>(hole), b_part_boxes, nullptr))
        a_rings.push_back({&hole, &polygon.edge_types[1 + k]});
      else
        aside.push_back({hole, polygon.edge_types[1 + k]});
    }
  }
  TypedOpResult result{true, {}, {}, {}, 0};
  const bool holes_set_aside = !aside.empty();
  if (!a_rings.empty()) {
    if (options.boost_overlay) {
      const TypedMultiPolygon a_part = copy_polygons(a_rings, a_starts), b_part = copy_polygons(b_rings, b_starts);
      MultiPolygon geometry;
      try {
        bg::union_(geometry_of(a_part), geometry_of(b_part), geometry);
      } catch (const std::exception& e) {
        return failed(std::string("union failed: ") + e.what());
      }
      EdgeTypeIndex index;
      if (options.assign_edge_types && !options.uniform_type) {
        index.add(a_part);
        index.add(b_part);
        index.build();
      }
      result = finish(std::move(geometry), index, kClipSearchRadius, options);
      refuse_out_of_bounds(a_rings, b_rings, OverlayOp::kUnion, result);
    } else {
      edge_overlay(a_rings, b_rings, OverlayOp::kUnion, options, result);
    }
    if (!result.ok) return result;
    if (!put_back_holes(result.polygons, std::move(aside)))
      return failed("union: a hole set aside has no polygon to return to");
  }
  // The overlay's output was checked alone. The whole result is checked
  // again when polygons were copied past the overlay or holes put back:
  // - a copy may touch the output (valid operands may touch at a point),
  //   and the overlay moves the output's edges onto its grid (by up to
  //   kOverlayMovesM) but not the copy, which took no part: it can then
  //   overlap them;
  // - a hole set aside may touch its outer ring, and the same move leaves
  //   the hole's vertex outside it;
  // - bg::is_valid rounds onto a grid scaled to the box of what it checks,
  //   so an output it accepts alone or with its near copies can be a
  //   disconnected interior or an overlap once a far copy widens the box.
  // (The typed_ops fuzzer found each: fuzz/known/README.md.) The cheap
  // test settles most; Boost only what it cannot vouch for. PolygonMap
  // checks each tile at the end of an insert instead (validate off); the
  // explorer's live view is not checked (validate off: live_view.cpp).
  bool copied = false;
  auto copy = [&](const TypedPolygon& polygon) {
    result.polygons.push_back(polygon);
    copied = true;
  };
  for (std::size_t j = 0; j < b.size(); ++j)
    if (!b_involved[j]) copy(b[j]);
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!a_involved[i]) {
      copy(a[i]);
      ++result.unchanged_tail;
    }
  const bool recheck = options.validate && !a_rings.empty() && (copied || holes_set_aside);
  if (recheck) {
    std::string why;
    if (!is_valid_cheap_first(result.polygons, why))
      return failed("union: the result with the holes and polygons it left alone is invalid: " + why);
  }
  return result;
}

namespace {

TypedOpResult boost_difference(const TypedMultiPolygon& a, const TypedMultiPolygon& b,
                               std::optional<EdgeType> a_type, std::optional<EdgeType> b_type,
                               const TypedOpOptions& options) {
  MultiPolygon geometry;
  try {
    bg::difference(geometry_of(a), geometry_of(b), geometry);
  } catch (const std::exception& e) {
    return failed(std::string("difference failed: ") + e.what());
  }
  EdgeTypeIndex index;
  if (options.assign_edge_types) {
    if (a_type) index.add_as(a, *a_type); else index.add(a);
    if (b_type) index.add_as(b, *b_type); else index.add(b);
    index.build();
  }
  return finish(std::move(geometry), index, kClipSearchRadius, options);
}

}  // namespace

TypedOpResult typed_difference(const TypedMultiPolygon& a, const TypedMultiPolygon& b,
                               std::optional<EdgeType> a_type, std::optional<EdgeType> b_type,
                               const TypedOpOptions& options) {
  std::vector<RingRef> a_rings, b_rings;
  add_rings(a, a_rings);
  add_rings(b, b_rings);
  if (options.boost_overlay) {
    TypedOpResult result = boost_difference(a, b, a_type, b_type, options);
    refuse_out_of_bounds(a_rings, b_rings, OverlayOp::kDifference, result);
    return result;
  }
  TypedOpResult result;
  edge_overlay(a_rings, b_rings, OverlayOp::kDifference, options, result, {a_type, b_type});
  return result;
}

TypedOpResult typed_clip(const TypedMultiPolygon& polygons, const Box& box,
                         const TypedOpOptions& options) {
  TypedOpOptions clip_options = options;
  clip_options.border_box = box;
  TypedOpResult result;
  result.ok = true;
  // Polygon by polygon: one far from the box is skipped, one well inside is
  // copied with its types, only the ones crossing a side are clipped (a
  // multi-polygon's parts are disjoint, so their pieces are too).
  const double margin = 1e-6;
  const Ring box_ring{box.min_corner(), Point(box.max_corner().x(), box.min_corner().y()), box.max_corner(),
                      Point(box.min_corner().x(), box.max_corner().y()), box.min_corner()};
  const std::vector<EdgeType> box_types(4, EdgeType::kBorder);
  const RingRef box_rings[1] = {{&box_ring, &box_types}};
  std::vector<RingRef> polygon_rings;
  bool clipped = false;
  const Box inner(Point(box.min_corner().x() + margin, box.min_corner().y() + margin),
                  Point(box.max_corner().x() - margin, box.max_corner().y() - margin));
  for (const auto& polygon : polygons) {
    Box envelope;
    bg::envelope(polygon.geometry, envelope);
    if (bg::disjoint(envelope, box)) continue;
    if (bg::within(envelope, inner)) {
      result.polygons.push_back(polygon);
      continue;
    }
    TypedOpResult piece;
    polygon_rings.clear();
    add_rings(polygon, polygon_rings);
    if (options.boost_overlay) {
      MultiPolygon geometry;
      try {
        bg::intersection(polygon.geometry, box, geometry);
      } catch (const std::exception& e) {
        return failed(std::string("clip failed: ") + e.what());
      }
      EdgeTypeIndex index;
      if (options.assign_edge_types && !options.uniform_type) {
        index.add(polygon);
        index.build();
      }
      piece = finish(std::move(geometry), index, kClipSearchRadius, clip_options);
      refuse_out_of_bounds(polygon_rings, box_rings, OverlayOp::kIntersection, piece);
    } else {
      edge_overlay(polygon_rings, box_rings, OverlayOp::kIntersection, clip_options, piece);
    }
    if (!piece.ok) return piece;
    result.reassign.edges += piece.reassign.edges;
    result.reassign.candidates += piece.reassign.candidates;
    for (auto& p : piece.polygons) result.polygons.push_back(std::move(p));
    clipped = true;
  }
  // Each piece was checked alone; pieces of polygons that touch at a point
  // can overlap once the overlay moved an edge onto its grid (as in
  // typed_union above): with validate on, the whole result is checked.
  std::string why;
  if (options.validate && clipped && result.polygons.size() > 1 && !is_valid_cheap_first(result.polygons, why))
    return failed("clip: the pieces together are invalid: " + why);
  return result;
}

TypedOpResult typed_offset(const TypedMultiPolygon& polygons, double distance_m,
                           int points_per_circle, const TypedOpOptions& options) {
  namespace bs = bg::strategy::buffer;
  MultiPolygon geometry;
  try {
    bg::buffer(geometry_of(polygons), geometry, bs::distance_symmetric<double>(distance_m),
               bs::side_straight(), bs::join_round(points_per_circle), bs::end_round(points_per_circle),
               bs::point_circle(points_per_circle));
  } catch (const std::exception& e) {
    return failed(std::string("offset failed: ") + e.what());
  }
  EdgeTypeIndex index;
  if (options.assign_edge_types) {
    index.add(polygons);
    index.build();
  }
  return finish(std::move(geometry), index, std::abs(distance_m) + kClipSearchRadius, options);
}

}  // namespace pex::mapping
