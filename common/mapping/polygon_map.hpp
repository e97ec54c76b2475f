#pragma once
// The polygonal map (paper, section 3.3 "Map representation"), kept in square
// tiles so that inserting a scan touches only the part of the map it overlaps.
//
// - free space: the union of the scan polygons (edges obstacle / frontier);
// - obstacles: the scans' obstacle edges widened into a band (obstacle_inner_m
//   into the free side, obstacle_outer_m beyond the wall), unioned;
// - planning map: free space minus obstacles; edges from the free map are
//   frontiers, edges from the obstacle map are obstacles.
// Each is stored per tile, clipped to the tile's box (box edges typed kBorder).
// The merged maps (free_space(), planning_map()) are the union of the tiles
// with the borders dissolved.
//
// Tiles are immutable and shared (std::shared_ptr<const Tile>): copying a
// PolygonMap copies only the tile table, and an insert replaces the tiles it
// touches, so maps copied for SLAM particles share every untouched tile.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "mapping/typed_ops.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

struct PolygonMapOptions {
  double tile_size_m = 8.0;
  // Tile lines are at tile_origin_m + k * tile_size_m. Not a round number, so
  // walls of drawn worlds (at whole centimetres) do not run along tile lines.
  double tile_origin_m = 0.0137;
  // Obstacle band around each obstacle polyline of a scan (asymmetric: the
  // free side loses little area, noise beyond the wall is cut).
  double obstacle_inner_m = 0.02;
  double obstacle_outer_m = 0.10;
  // RDP tolerance after every operation (0 = off). Never merges edge types.
  double simplify_epsilon_m = 0.01;
  // false: plain geometry, all edges frontier (benchmark baseline).
  bool assign_edge_types = true;
};

// One square of the map. An insert writes free and obstacles; the planning
// layer (free minus obstacles) is derived from them on first use and kept.
// Why lazily: only a map that is published or planned on needs it, and with
// one map per SLAM particle most tile versions are never read before the next
// insert replaces them (the difference was a third of an insert's cost).
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
  // The planning layer came from Boost's difference (our edge overlay's
  // result failed a check): counted by the merge.
  bool planning_by_boost() const;
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
  mutable bool planning_by_boost_ = false;
};

struct InsertResult {
  bool ok = false;          // false: at least one tile kept its old state
  std::string error;        // the first failure's reason
  int tiles_touched = 0;
  int tiles_failed = 0;
  // Free area of the updated tiles before the insert and right after the
  // union (before simplification): a union never shrinks it.
  double free_area_before_m2 = 0.0;
  double free_area_after_union_m2 = 0.0;
  ReassignStats reassign;
  // Overlays redone with Boost.Geometry because our edge overlay failed or
  // its result failed a check (typed_ops.hpp, edge_overlay.hpp).
  int boost_fallbacks = 0;
};

struct MergeResult {
  bool ok = false;
  std::string error;
  TypedMultiPolygon polygons;
  std::int64_t stray_border_edges = 0;  // tile-border edges left after merging (typed frontier)
  // Tiles whose planning layer could not be derived from their free and
  // obstacle layers: they took part with their last good planning layer.
  std::int64_t stale_planning_tiles = 0;
  // Fallbacks to Boost.Geometry: the tiles were united by Boost's cascade
  // (the edge overlay's result failed its check); tiles whose planning layer
  // is Boost's difference.
  bool boost_cascade = false;
  std::int64_t boost_planning_tiles = 0;
};

// The obstacle band of a scan polygon: each maximal chain of obstacle edges
// buffered `inner_m` to its left (free side of a counter-clockwise ring) and
// `outer_m` to its right, with flat ends and round joins.
// Built directly chain by chain (direct_obstacle_band), else by Boost's
// buffer of the chains. Checked valid either way: an invalid band comes back
// empty, with the reason in *why if given.
MultiPolygon obstacle_band(const TypedPolygon& scan, double inner_m, double outer_m,
                           std::string* why = nullptr);

// The maximal chains of obstacle edges of a scan polygon (what the band covers).
using Chain = bg::model::linestring<Point>;
using Chains = bg::model::multi_linestring<Chain>;
Chains obstacle_chains(const TypedPolygon& scan);

// The band built chain by chain (right offset by outer_m, left by inner_m,
// round outer joins, flat ends): nullopt unless every chain is open, every
// join can be built by meeting offset lines and every chain's band is
// clearly valid; bands that overlap are united (typed_union). obstacle_band
// falls back to Boost's buffer otherwise.
std::optional<MultiPolygon> direct_obstacle_band(const Chains& chains, double inner_m, double outer_m);

// A scan polygon and its obstacle band, ready to insert. The band depends on
// the scan alone and moves with it, so the per-particle maps of SLAM build it
// once per scan in the sensor frame and move both to every particle's pose.
struct PreparedScan {
  TypedPolygon polygon;
  MultiPolygon band;
  std::string band_error;  // not empty: no band could be built (the scan goes in without one)
};
// Builds the band with the map options' obstacle_inner_m / obstacle_outer_m
// (obstacle_band, which checks it).
PreparedScan prepare_scan(TypedPolygon scan, const PolygonMapOptions& options);

class PolygonMap {
 public:
  explicit PolygonMap(PolygonMapOptions options = {});

  // Inserts one scan polygon (map frame, valid, see scan_to_polygon). A tile
  // whose update fails or yields an invalid polygon keeps its last good state;
  // the failure is counted and the rest of the scan still goes in.
  InsertResult insert(const TypedPolygon& scan);
  // The same with the band already built (prepare_scan, moved rigidly).
  InsertResult insert(const PreparedScan& scan);

  // The merged maps (cost grows with the whole map: call at publication rate),
  // simplified with options().simplify_epsilon_m unless another is given.
  MergeResult free_space(std::optional<double> simplify_epsilon_m = std::nullopt) const;
  MergeResult planning_map(std::optional<double> simplify_epsilon_m = std::nullopt) const;

  // Sums over tiles (tile-border vertices included). planning_vertex_count()
  // derives the planning layer of every tile that has not got it yet.
  std::size_t free_vertex_count() const;
  std::size_t planning_vertex_count() const;
  double free_area_m2() const;
  std::size_t tile_count() const { return tiles_.size(); }
  // Heap bytes of the tiles' geometry, types and table.
  std::size_t memory_bytes() const;
  std::int64_t scans_inserted() const { return scans_inserted_; }
  std::int64_t failed_tile_updates() const { return failed_tile_updates_; }
  // Overlays of inserts that fell back to Boost.Geometry (InsertResult).
  std::int64_t boost_fallbacks() const { return boost_fallbacks_; }
  const PolygonMapOptions& options() const { return options_; }

  using TileKey = std::pair<std::int32_t, std::int32_t>;
  // Read access for tests, memory accounting and checkpoints (ordered: deterministic).
  const std::map<TileKey, std::shared_ptr<const Tile>>& tiles() const { return tiles_; }

  // For checkpoints (map_archive.hpp): puts a tile back as it was saved (its
  // free and obstacle layers, valid and clipped to the tile's box); the
  // planning layer is derived again on first use, as after an insert.
  void restore_tile(const TileKey& key, TypedMultiPolygon free, TypedMultiPolygon obstacles);
  void restore_counters(std::int64_t scans_inserted, std::int64_t failed_tile_updates, std::int64_t boost_fallbacks);

 private:
  Box tile_box(const TileKey& key) const;
  enum class Layer { kFree, kPlanning };
  MergeResult merge(Layer layer, double simplify_epsilon_m) const;

  PolygonMapOptions options_;
  std::map<TileKey, std::shared_ptr<const Tile>> tiles_;
  std::int64_t scans_inserted_ = 0;
  std::int64_t failed_tile_updates_ = 0;
  std::int64_t boost_fallbacks_ = 0;
};

// Splits every edge where it crosses a grid line x = origin_m + k * cell_m or
// y = origin_m + k * cell_m, with crossing points computed from the edge alone (the same
// bits in both neighbouring tiles), so clipping to tiles adds no new rounding.
void split_at_grid(MultiPolygon& geometry, double cell_m, double origin_m = 0.0);
// The same for a typed polygon: the pieces of an edge keep its type.
void split_at_grid(TypedPolygon& polygon, double cell_m, double origin_m = 0.0);

}  // namespace pex::mapping
