#pragma once
// Union, intersection and difference of two valid typed multi-polygons by
// splitting their edges where they meet, keeping the pieces that bound the
// result and linking them into rings. Every output edge is a piece of exactly one input edge, so
// it carries that edge's type: no search for the best-matching input edge is
// needed (it is the zero-penalty match of the reassignment pass by
// construction).
//
// Why our own: PolygonMap's updates are small overlays (a tile of a few
// hundred vertices and a scan piece), where Boost.Geometry's overlay costs
// mostly set-up (sections, turn bookkeeping, traversal state; figures in
// docs/mapping.md) and needs the reassignment pass afterwards. This one finds meeting edges through a grid
// and sorts only the split points, so on map-like inputs its cost grows about
// linearly with the vertices and meeting points; its buffers are reused.
//
// Robustness: points within kOverlaySnap (1e-9 m) of each other or of an edge
// are treated as meeting it (b's vertices are moved onto a's, edges are split
// at the other side's vertices), so touching and overlapping edges, which
// tiles and their pieces have along every tile border, become shared pieces.
// The result is not checked here: callers check it (is_clearly_valid, then
// bg::is_valid, after RDP: simplify_and_check in tile.hpp) and count a
// failure when it is not valid or `ok` is false. Boost.Geometry's overlay is
// the oracle of the tests, not a fallback.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

enum class OverlayOp { kUnion, kIntersection, kDifference };

inline constexpr double kOverlaySnap = 1e-9;

struct OverlayResult {
  bool ok = false;
  std::string error;  // why not ok: pieces that do not link into rings, a hole with no polygon
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
