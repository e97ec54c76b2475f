#pragma once
// The square tiles of PolygonMap: lines at origin_m + k * size_m on both axes,
// tile (i, j) the box between lines i, i + 1 and j, j + 1. Every coordinate on
// a tile line is computed by one expression (line()), and an edge is split at
// the lines it crosses with crossing points computed from the edge alone in a
// canonical direction, so both neighbours of a line see the same bits and
// clipping to tiles adds no rounding.
#include <cstdint>
#include <utility>

#include "mapping/edge_overlay.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

using TileKey = std::pair<std::int32_t, std::int32_t>;

struct TileGrid {
  double size_m = 8.0;
  double origin_m = 0.0;

  // Coordinate of line k, on the overlay's grid (so overlays leave a tile's
  // sides where they are); index of the tile column (row) holding v.
  double line(std::int64_t k) const { return to_overlay_grid(origin_m + static_cast<double>(k) * size_m); }
  std::int32_t index(double v) const;
  Box box(const TileKey& key) const;
  // The keys of the tiles an envelope meets: [first.first, last.first] x [first.second, last.second].
  std::pair<TileKey, TileKey> range(const Box& envelope) const;
};

// Splits every edge where it crosses a grid line x = origin_m + k * cell_m or
// y = origin_m + k * cell_m, with crossing points computed from the edge alone (the same
// bits in both neighbouring tiles), so clipping to tiles adds no new rounding.
void split_at_grid(MultiPolygon& geometry, double cell_m, double origin_m = 0.0);
// The same for a typed polygon: the pieces of an edge keep its type.
void split_at_grid(TypedPolygon& polygon, double cell_m, double origin_m = 0.0);

// The part of `polygon` inside `tile` (a tile's box: its sides on grid lines),
// exactly: every vertex of the result is one of the polygon's or a corner of
// the box, with the types the overlay's clip gives (an edge on a side of the
// box kBorder, like the stretches of the sides added). For a polygon split at
// the grid's lines (split_at_grid), whose edges each lie in one tile, this is
// a walk along the rings that joins the runs of edges inside the box along
// its sides, in a fraction of an overlay's time.
//
// Returns false, with `out` as it was, where the polygon meets the box
// otherwise: an edge from inside the box to outside it or across it (not
// split at the box's lines), the boundary touching a side where it neither
// enters nor leaves the box, two runs meeting at one point of a side, or a
// hole inside the box with more than one piece around it. Those are left to
// the overlay (typed_clip), which handles every case.
bool clip_split_to_tile(const TypedPolygon& polygon, const Box& tile, TypedMultiPolygon& out);

}  // namespace pex::mapping
