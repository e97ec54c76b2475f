#pragma once
// One tile of PolygonMap with its lazily derived planning layer, and the
// check every layer passes before it is stored.
#include <cstddef>
#include <memory>
#include <mutex>
#include <span>
#include <string>

#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

// The last step of every layer update (insert, planning layer, merge): RDP
// of the first `changed` polygons of `layer` with epsilon_m, run by run of
// equal type, then one validity check of them together with the other
// polygons (kept: unchanged, valid, interior-disjoint from the changed ones
// before RDP) whose boxes meet theirs: RDP moves a boundary by up to
// epsilon_m, so a simplified polygon can cross a kept neighbour. A changed
// polygon is_clearly_valid cannot clear is simplified again with a finer
// tolerance (epsilon_m / 4, / 16, then not at all) until it can, in at
// most six rounds; what it still cannot clear bg::is_valid decides. If that is not valid, RDP polygon
// by polygon (each keeping its own validity), then no RDP. False, with the
// reason in `why`, if none of them is valid (the changed polygons are then as
// they came). The kept polygons are reordered (those near the changed ones
// first) but not changed.
bool simplify_and_check(TypedMultiPolygon& layer, std::size_t changed, double epsilon_m, std::string& why);

// One square of the map. An insert writes free and obstacles; the planning
// layer (free minus obstacles) is derived from them on first use and kept.
// Why lazily: only a map that is published or planned on needs it, and with
// one map per SLAM particle most tile versions are never read before the next
// insert replaces them (docs/mapping.md: what that saves per insert).
// Thread-safe: a tile shared by several particle maps may be asked for its
// planning layer from several threads; it is computed once.
class Tile {
 public:
  struct PlanningOptions {
    double simplify_epsilon_m = 0.0;
    bool assign_edge_types = true;
  };
  // `last_good_planning`: the newest planning layer computed for an earlier
  // version of this tile (null if none); planning() falls back to it if the
  // difference fails, so a failure keeps the last good state.
  Tile(Box box, TypedMultiPolygon free, TypedMultiPolygon obstacles,
       std::shared_ptr<const TypedMultiPolygon> last_good_planning, PlanningOptions options);
  Tile(const Tile&) = delete;
  Tile& operator=(const Tile&) = delete;

  Box box;
  TypedMultiPolygon free;       // obstacle / frontier / border
  TypedMultiPolygon obstacles;  // obstacle / border

  // Free minus obstacles: frontier / obstacle / border. Computed on the first call.
  const TypedMultiPolygon& planning() const;
  // Computed already (planning() costs nothing), and whether that failed:
  // then planning() is the last good layer (or empty) and planning_error() says why.
  bool planning_computed() const;
  bool planning_failed() const;
  std::string planning_error() const;
  // For the next version of this tile: this tile's planning layer if it has
  // been computed and is its own, else the one this tile would fall back to.
  std::shared_ptr<const TypedMultiPolygon> last_good_planning() const;
  // Heap bytes of the layers (the planning layer once computed, fallback included).
  std::size_t memory_bytes() const;

 private:
  // Caller holds mutex_.
  void compute_planning() const;

  PlanningOptions options_;
  mutable std::mutex mutex_;  // guards the members below
  mutable std::shared_ptr<const TypedMultiPolygon> fallback_;  // released once computed
  mutable std::shared_ptr<const TypedMultiPolygon> planning_;  // null until computed
  mutable std::string error_;  // empty unless the difference failed
};

}  // namespace pex::mapping
