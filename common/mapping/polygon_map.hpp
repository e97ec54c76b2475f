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
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "mapping/obstacle_band.hpp"
#include "mapping/tile.hpp"
#include "mapping/tile_grid.hpp"
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
  // Each obstacle chain's band ends this far short of the chain's ends
  // (obstacle_band.hpp says why: doors narrowed by the union of the jambs'
  // bands). 0: the whole chain.
  double obstacle_end_trim_m = 0.0;
  // RDP tolerance after every operation (0 = off). Never merges edge types.
  double simplify_epsilon_m = 0.01;
  // false: plain geometry, all edges frontier (benchmark baseline).
  bool assign_edge_types = true;
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
};

struct MergeResult {
  bool ok = false;
  std::string error;
  TypedMultiPolygon polygons;
  std::int64_t stray_border_edges = 0;  // tile-border edges left after merging (typed frontier)
  // Tiles whose planning layer could not be derived from their free and
  // obstacle layers: they took part with their last good planning layer.
  std::int64_t stale_planning_tiles = 0;
};

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

  // Inserts one scan polygon (map frame, valid, see scan_to_polygon). Every
  // stored layer is valid (checked with its neighbours after RDP). A tile
  // whose update fails keeps its last good state; the failure is counted
  // (failed_tile_updates) and the rest of the scan still goes in.
  InsertResult insert(const TypedPolygon& scan);
  // The same with the band already built (prepare_scan, moved rigidly).
  InsertResult insert(const PreparedScan& scan);

  // The merged maps (cost grows with the whole map: call at publication rate),
  // simplified with options().simplify_epsilon_m unless another is given.
  // ok: the polygons are valid (the simplified ones checked with every
  // polygon near them); else an error and no polygons.
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
  const PolygonMapOptions& options() const { return options_; }

  using TileKey = mapping::TileKey;
  // Read access for tests, memory accounting and checkpoints (ordered: deterministic).
  const std::map<TileKey, std::shared_ptr<const Tile>>& tiles() const { return tiles_; }

  // For checkpoints (map_archive.hpp): puts a tile back as it was saved (its
  // free and obstacle layers, valid and clipped to the tile's box); the
  // planning layer is derived again on first use, as after an insert.
  void restore_tile(const TileKey& key, TypedMultiPolygon free, TypedMultiPolygon obstacles);
  void restore_counters(std::int64_t scans_inserted, std::int64_t failed_tile_updates);

 private:
  enum class Layer { kFree, kPlanning };
  MergeResult merge(Layer layer, double simplify_epsilon_m) const;

  PolygonMapOptions options_;
  TileGrid grid_;
  std::map<TileKey, std::shared_ptr<const Tile>> tiles_;
  std::int64_t scans_inserted_ = 0;
  std::int64_t failed_tile_updates_ = 0;
};

}  // namespace pex::mapping
