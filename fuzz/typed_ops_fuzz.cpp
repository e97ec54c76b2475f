// The typed overlay (mapping::typed_union, typed_difference, typed_clip) on
// adversarial polygons: vertices on a coarse grid (shared vertices,
// collinear and touching edges, holes touching their outer ring), some moved
// by a hair (1e-9 m, far below the overlay's grid) or far away.
//
// Input: two operands, each up to 3 polygons: per polygon a vertex count
// (3..10), vertices as grid bytes (with a "hair" flag), edge types, and an
// optional hole. Operands that are not valid typed multipolygons (the
// operations' precondition: bg::is_valid, and what it cannot judge at far
// extents, holes_inside_and_area_positive) are skipped.
// Invariants: nothing crashes; each result is either refused with a reason
// or valid, typed on every edge, and of a plausible area: a union covers
// each operand and no more than both, a difference no more than its first
// operand, a clip no more than the operand or the box. And the tile clip of
// the map's insert (clip_split_to_tile): each polygon of the first operand
// split at a grid of 0.75 m through the input's grid points (vertices on
// lines, edges along them); every tile the walk clips is valid and has the
// overlay's area, and the tiles' areas add up to the polygon's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <span>
#include <sstream>
#include <string>

#include <boost/geometry.hpp>

#include "fuzz_check.hpp"
#include "fuzz_input.hpp"
#include "mapping/tile_grid.hpp"
#include "mapping/typed_ops.hpp"
#include "mapping/typed_polygon.hpp"

namespace {

using namespace pex;
using namespace pex::mapping;
namespace bg = boost::geometry;

Ring read_ring(fuzz::Input& in, std::vector<EdgeType>& types) {
  Ring ring;
  const int n = 3 + in.byte() % 8;
  for (int i = 0; i < n; ++i) {
    const std::uint8_t g = in.byte();
    const std::uint8_t nudge = in.byte();
    double x = (g & 0xF) * 0.25, y = (g >> 4) * 0.25;
    if (nudge & 1) x += (nudge & 2 ? 1e-9 : -1e-9);
    if (nudge & 4) y += (nudge & 8 ? 1e-9 : -1e-9);
    if (nudge == 0xFF) x *= 1e6;  // far away
    ring.push_back(Point(x, y));
    types.push_back(static_cast<EdgeType>((nudge >> 4) % 3));
  }
  ring.push_back(ring.front());
  return ring;
}

TypedMultiPolygon read_operand(fuzz::Input& in) {
  TypedMultiPolygon out;
  const int polygons = in.byte() % 4;
  for (int p = 0; p < polygons; ++p) {
    TypedPolygon poly;
    std::vector<EdgeType> types;
    poly.geometry.outer() = read_ring(in, types);
    poly.edge_types.push_back(types);
    if (in.byte() & 1) {
      std::vector<EdgeType> hole_types;
      poly.geometry.inners().push_back(read_ring(in, hole_types));
      poly.edge_types.push_back(hole_types);
    }
    bg::correct(poly.geometry);  // orientation only; a ring it reverses keeps its count of types
    out.push_back(std::move(poly));
  }
  return out;
}

// Necessary for a valid operand, and beyond what bg::is_valid can judge at
// this input's extents: it decides on a grid of about 1e-7 of the extent, so
// with a vertex 1e6 times farther out it merges everything below about
// 0.4 m and called a hole 3750 km outside its 3.75 m outer ring valid
// (fuzz/known/README.md). Each hole's box must lie in its outer ring's box,
// and each polygon must have a positive area.
bool holes_inside_and_area_positive(const TypedMultiPolygon& operand) {
  for (const auto& polygon : operand) {
    const auto outer = bg::return_envelope<Box>(polygon.geometry.outer());
    for (const auto& hole : polygon.geometry.inners())
      if (!bg::covered_by(bg::return_envelope<Box>(hole), outer)) return false;
    if (!(bg::area(polygon.geometry) > 0.0)) return false;
  }
  return true;
}

// boundary_m: the operands' boundary length when our overlay computed the
// result (it rounds onto its grid, moving the boundary by up to
// kOverlayMovesM), 0 for Boost's.
void check_result(const TypedOpResult& r, const char* op, double lo, double hi, double boundary_m) {
  if (!r.ok) {
    PEX_FUZZ_CHECK(!r.error.empty(), std::string(op) + " refused without a reason");
    return;
  }
  std::string why;
  PEX_FUZZ_CHECK(is_valid(r.polygons, &why), std::string(op) + " gave invalid polygons: " + why);
  const double a = area(r.polygons);
  const double tolerance = 1e-6 * std::max(1.0, hi) + boundary_m * kOverlayMovesM;
  PEX_FUZZ_CHECK(a >= lo - tolerance && a <= hi + tolerance,
                 std::string(op) + " area " + std::to_string(a) + " not in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
}

// The polygon, the tile and the walk's piece, to the last bit.
std::string case_of(const TypedPolygon& split, const Box& box, const TypedMultiPolygon& walked) {
  std::ostringstream out;
  out << std::setprecision(17) << "\n  split polygon " << bg::wkt(split.geometry) << "\n  tile " << bg::wkt(box)
      << "\n  walked " << bg::wkt(geometry_of(walked));
  return out.str();
}

// The walk's tiles against the overlay's clip of the same split polygon.
void check_tile_clips(const TypedPolygon& polygon) {
  const TileGrid grid{0.75, 0.25};
  const auto [first, last] = grid.range(bg::return_envelope<Box>(polygon.geometry));
  if (last.first - first.first > 8 || last.second - first.second > 8) return;  // a vertex far away
  TypedPolygon split = polygon;
  split_at_grid(split, grid.size_m, grid.origin_m);
  // split_at_grid puts crossings within 1e-9 m of a line on it, which can
  // fold a feature of a hair's width over: the overlay and the walk then
  // answer differently and neither is wrong, and bg::is_valid's verdict on
  // such a polygon changes with the compiler's rounding (this one was valid
  // to clang's build, not to gcc's). The walk's pieces must be valid where
  // the split polygon is; their areas are compared with the overlay's where
  // it is clearly valid (is_clearly_valid: no feature near Boost's grid).
  const bool valid = is_valid(split);
  const bool comparable = valid && is_clearly_valid(std::span(&split, 1));
  const double whole = bg::area(split.geometry), boundary = bg::perimeter(split.geometry);
  double walked_sum = 0.0;
  bool all_walked = true;
  for (auto i = first.first; i <= last.first; ++i)
    for (auto j = first.second; j <= last.second; ++j) {
      const Box box = grid.box({i, j});
      TypedMultiPolygon walked;
      if (!clip_split_to_tile(split, box, walked)) {
        all_walked = false;
        continue;
      }
      if (!valid) continue;
      std::string why;
      PEX_FUZZ_CHECK(is_valid(walked, &why), "tile clip gave invalid polygons: " + why + case_of(split, box, walked));
      walked_sum += area(walked);
      if (!comparable) continue;
      const auto overlaid = typed_clip({split}, box);  // it types the box's sides kBorder itself
      const double tolerance = 1e-9 * std::max(1.0, whole) + (boundary + 4 * grid.size_m) * kOverlayMovesM;
      if (overlaid.ok)
        PEX_FUZZ_CHECK(std::abs(area(walked) - area(overlaid.polygons)) <= tolerance,
                       "tile clip area " + std::to_string(area(walked)) + " against the overlay's " +
                           std::to_string(area(overlaid.polygons)) + case_of(split, box, walked));
    }
  if (all_walked && comparable)
    PEX_FUZZ_CHECK(std::abs(walked_sum - whole) <= 1e-9 * std::max(1.0, whole),
                   "tile clips add up to " + std::to_string(walked_sum) + ", the polygon is " + std::to_string(whole));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  const TypedMultiPolygon a = read_operand(in);
  const TypedMultiPolygon b = read_operand(in);
  if (!is_valid(a) || !is_valid(b) || !holes_inside_and_area_positive(a) || !holes_inside_and_area_positive(b)) return 0;
  const double area_a = area(a), area_b = area(b);
  TypedOpOptions options;
  options.boost_overlay = in.byte() & 1;
  const Box box(Point(0.5, 0.5), Point(2.75, 2.25));
  const double perimeter_a = bg::perimeter(geometry_of(a)), perimeter_b = bg::perimeter(geometry_of(b));
  const double rounded = options.boost_overlay ? 0.0 : 1.0;
  check_result(typed_union(a, b, options), "union", std::max(area_a, area_b), area_a + area_b,
               rounded * (perimeter_a + perimeter_b));
  check_result(typed_difference(a, b, std::nullopt, std::nullopt, options), "difference",
               std::max(0.0, area_a - area_b), area_a, rounded * (perimeter_a + perimeter_b));
  check_result(typed_clip(a, box, options), "clip", 0.0, std::min(area_a, bg::area(box)),
               rounded * (perimeter_a + bg::perimeter(box)));
  for (const auto& polygon : a) check_tile_clips(polygon);
  return 0;
}
