#pragma once
// The free space shrunk by the robot's radius: the offset under the C-space
// (cspace.hpp), computed by Clipper on a 10 um integer grid, tile by tile
// where a polygon is large, with the tiles' results kept between plans.
//
// Why tiles: the explorer plans every few metres on a map that changed near
// the robot only, and Clipper's offset of a whole large map (thousands of
// ragged wall vertices) was most of a plan's time. The shrunk free space
// within a tile depends only on the map within the offset distance of the
// tile, so a tile whose map there did not change keeps its result.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "mapping/typed_ops.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct InwardOffset {
  double distance_m = 0.3;  // > 0
  // Round joins: at least this many vertices per full circle, and chords
  // within 1 mm of the arc (a chord cuts into the clearance).
  int points_per_circle = 16;
  // true: each output edge typed as the map edge it was offset from
  // (mapping::assign_types); false: every edge kObstacle.
  bool type_edges = true;
  // Side of the square tiles (on a grid fixed in the map frame) a polygon of
  // at least tile_min_vertices is offset in; 0: every polygon whole. A
  // polygon whose box averages more than tile_min_vertices per tile of this
  // side gets tiles of half the side, or a quarter (a ragged, scanned map;
  // tile_min_vertices 0: always this side).
  double tile_m = 12.0;
  int tile_min_vertices = 400;
  // > 0: the result simplified (Ramer-Douglas-Peucker), its boundary moving
  // by at most this much: a polygon offset whole after the offset
  // (mapping::simplify_typed), a tiled one tile by tile before the tiles are
  // united (the union then costs a fraction: most of a tile's vertices are
  // the round joins' arcs), but for the seams: within a band along each
  // tile's sides its vertices are kept, and the union of the tiles is
  // simplified by a little (kSeamEpsilonM, 0.5 mm), the tiles by the rest.
  // A tile whose simplified rings would meet, or cannot be shown apart
  // within 64 pair tests per edge, keeps them as they were.
  double simplify_epsilon_m = 0.0;
};

// Offset results kept between calls of offset_inward(): each keyed by the
// exact input it was computed from (a tile's map edges, in grid units, and
// whether the tile's centre is inside the polygon; or a whole small
// polygon), so a result taken from here is bit for bit the one computing it
// again would give: the offset is a function of the map alone, cache or not.
// Entries not used by the last kKeptCalls calls are dropped (the planner
// alternates between the normal and the tight clearance, whose offsets
// differ). Not thread-safe: one per planning thread.
class OffsetTileCache {
 public:
  OffsetTileCache();
  ~OffsetTileCache();
  OffsetTileCache(const OffsetTileCache&) = delete;
  OffsetTileCache& operator=(const OffsetTileCache&) = delete;

  struct Counters {
    std::int64_t hits = 0;    // results taken from the cache
    std::int64_t misses = 0;  // results computed (and kept)
  };
  const Counters& counters() const { return counters_; }
  std::size_t entries() const;
  static constexpr int kKeptCalls = 4;

  struct Impl;  // inward_offset.cpp

 private:
  std::unique_ptr<Impl> impl_;
  Counters counters_;
  friend mapping::TypedOpResult offset_inward(const mapping::TypedMultiPolygon&, const InwardOffset&,
                                              OffsetTileCache*);
};

// The free space (interior-disjoint polygons: each is offset on its own, as
// its C-space depends on its own rings only) shrunk by how.distance_m:
// the Minkowski erosion by a disk, with round joins, computed by Clipper
// (ClipperLib::ClipperOffset, 10 um grid). A polygon of at least
// how.tile_min_vertices (and edges short beside a tile: listed in at most 32
// tiles per vertex on average) is cut into tiles of how.tile_m: each tile's result is
// the erosion of the polygon clipped to the tile grown by the distance and
// 1 cm, which is the whole polygon's erosion within the tile and a subset of
// it beyond (an erosion of less is less), and the tiles' results, which
// overlap, are united (so pieces join across tile sides). The same set as
// mapping::typed_offset(free_space, -distance_m, points_per_circle) up to the
// placement of the round joins' vertices and the grid. `cache` (may be null)
// keeps tile results between calls; the result does not depend on it.
// Refused (ok false, error set): a coordinate not finite or beyond 1e9 m.
mapping::TypedOpResult offset_inward(const mapping::TypedMultiPolygon& free_space, const InwardOffset& how,
                                     OffsetTileCache* cache = nullptr);

// The places within radius_m of the polyline `points` (its Minkowski sum with
// a disk: round ends and joins, chords within 1 mm of the arcs), on the same
// 10 um grid. Empty for no points, radius_m <= 0, or a coordinate not finite
// or beyond 1e9 m.
mapping::MultiPolygon dilated_polyline(const std::vector<mapping::Point>& points, double radius_m);
// ... of several polylines at once: the union of their dilations. Empty when
// any of them has a coordinate not finite or beyond 1e9 m.
mapping::MultiPolygon dilated_polylines(const std::vector<std::vector<mapping::Point>>& polylines, double radius_m);

// a united with b, and a less b (each a set of polygons with holes), on the
// same grid. Either side with a coordinate not finite or beyond 1e9 m: nullopt.
std::optional<mapping::MultiPolygon> united(const mapping::MultiPolygon& a, const mapping::MultiPolygon& b);
std::optional<mapping::MultiPolygon> subtracted(const mapping::MultiPolygon& a, const mapping::MultiPolygon& b);

}  // namespace pex::planning
