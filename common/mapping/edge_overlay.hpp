#pragma once
// Union, intersection and difference of two valid typed multi-polygons by
// splitting their edges where they meet, keeping the pieces that bound the
// result and linking them into rings. Every output edge is a piece of
// exactly one input edge, so it carries that edge's type: no search for the
// best-matching input edge is needed (it is the zero-penalty match of the
// reassignment pass by construction).
//
// Why our own: PolygonMap's updates are small overlays (a tile of a few
// hundred vertices and a scan piece), where Boost.Geometry's overlay costs
// mostly set-up (sections, turn bookkeeping, traversal state; figures in
// docs/mapping.md) and needs the reassignment pass afterwards. This one
// finds meeting edges and nearby vertices through bucket grids, so on
// map-like inputs its cost grows about linearly with the vertices and
// meeting points; its buffers are reused.
//
// Exact: the output lies on a grid of kOverlayGridM (2^-20 m, about 1 um),
// reached by snap rounding. The operands are taken as integers on a far
// finer grid (2^-40 m); their vertices and the crossings of an edge of a
// with one of b mark the output grid's cells they lie in "hot"; every edge
// is bent through the centre of every hot cell it passes, and the bent
// pieces again until none passes one it does not end in (iterated snap
// rounding). Every predicate after that (orientation, angle order, point in
// polygon, the polygon a hole belongs to) is computed on integers without
// rounding. The pieces meet only at their ends or along whole pieces, so
// classifying and linking them cannot disagree: for operands valid on the
// fine grid the overlay succeeds, and no vertex of its output lies within
// half a cell of an edge it is not on. It moves the boundary by about a
// cell (kOverlayMovesM). Touching and overlapping edges, which tiles and their
// pieces have along every tile border, become shared pieces; a sliver of
// one operand thinner than a cell collapses and is dropped. Boost.Geometry's
// overlay is the oracle of the tests, not a fallback.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

enum class OverlayOp { kUnion, kIntersection, kDifference };

// The overlay's grid, and the largest coordinate it takes (larger ones are
// refused: ok false). Products of coordinate differences then fit 128 bits.
inline constexpr int kOverlayGridBits = 20;
inline constexpr double kOverlayGridM = 1.0 / (1 << kOverlayGridBits);
inline constexpr double kOverlayMaxCoordinateM = 8192.0;
// How far the overlay moves its operands' boundary, as callers' area checks
// allow: a vertex goes to the centre of its cell (0.71 of a cell at most)
// and a piece bent through a hot cell moves as much again. Iterated snap
// rounding has no such bound in general (a piece bent round by round can
// drift further; Halperin and Packer), so a result beyond it is refused by
// those checks and counted, not taken.
inline constexpr double kOverlayMovesM = 2.0 * kOverlayGridM;

// v rounded to the overlay's grid as the overlay rounds a vertex (to the
// nearest line, a half up; v itself beyond kOverlayMaxCoordinateM). Tile
// lines lie on it, so a tile's sides are not moved.
double to_overlay_grid(double v);

struct OverlayResult {
  bool ok = false;
  // Why not ok: a coordinate not finite or beyond kOverlayMaxCoordinateM;
  // or, for operands that were not valid, pieces that do not link or a hole
  // with no polygon around it.
  std::string error;
  TypedMultiPolygon polygons;
};

// a op b (kDifference: a minus b). Both must be valid (outer rings
// counter-clockwise, holes clockwise, polygons interior-disjoint). Where an
// edge of a and an edge of b overlap, the piece bounds the union and the
// intersection when they run in the same direction (kept once), the
// difference when they run in opposite directions; kept, it takes the more
// specific type (obstacle before frontier before border). Output edges on a
// side of `border_box`, if given, are typed kBorder.
OverlayResult overlay(const TypedMultiPolygon& a, const TypedMultiPolygon& b, OverlayOp op,
                      const std::optional<Box>& border_box = std::nullopt);

// One ring of an operand, by reference: callers that pass a part of a
// multi-polygon (some of its polygons, some of their holes) need not copy it.
struct RingRef {
  const Ring* ring;
  const std::vector<EdgeType>* types;
};
void add_rings(const TypedPolygon& polygon, std::vector<RingRef>& rings);
void add_rings(const TypedMultiPolygon& polygons, std::vector<RingRef>& rings);

// The same on rings: a and b are the rings of valid multi-polygons. A type
// given in side_types[s] replaces the types of every edge of operand s (the
// planning map's difference: free edges frontier, obstacle edges obstacle).
OverlayResult overlay(std::span<const RingRef> a, std::span<const RingRef> b, OverlayOp op,
                      const std::optional<Box>& border_box = std::nullopt,
                      const std::optional<EdgeType> (&side_types)[2] = {});

}  // namespace pex::mapping
