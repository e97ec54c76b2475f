// Boost.Geometry 1.74 envelope code trips -Wmaybe-uninitialized when inlined
// into our code; the warning is in Boost, not here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "mapping/polygon_map.hpp"

#include <algorithm>
#include <cmath>

namespace pex::mapping {

namespace {

// What an insert puts into one tile: the scan and its band clipped to the box.
struct TilePiece {
  TileKey key;
  Box box;
  TypedMultiPolygon free;
  TypedMultiPolygon band;
};

TypedOpOptions op_options(const PolygonMapOptions& options, const Box& box, bool band) {
  TypedOpOptions typed;
  typed.assign_edge_types = options.assign_edge_types;
  typed.validate = false;  // each layer is checked once, at the end (simplify_and_check)
  typed.border_box = box;
  if (band) typed.uniform_type = EdgeType::kObstacle;
  return typed;
}

// One layer's part in one tile: each polygon meeting the tile's box clipped
// by the walk along the box (clip_split_to_tile: the polygons were split at
// the tile lines), or by the overlay where the walk leaves it.
TypedOpResult clip_split_layer(const TypedMultiPolygon& polygons, const std::vector<Box>& envelopes, const Box& box,
                               const TypedOpOptions& options) {
  TypedOpResult result{true, {}, {}, {}, 0};
  for (std::size_t k = 0; k < polygons.size(); ++k) {
    if (bg::disjoint(envelopes[k], box) || clip_split_to_tile(polygons[k], box, result.polygons)) continue;
    auto piece = typed_clip(TypedMultiPolygon{polygons[k]}, box, options);
    if (!piece.ok) return piece;
    for (auto& p : piece.polygons) result.polygons.push_back(std::move(p));
  }
  return result;
}

std::vector<Box> envelopes_of(const TypedMultiPolygon& polygons) {
  std::vector<Box> boxes;
  boxes.reserve(polygons.size());
  for (const auto& p : polygons) boxes.push_back(bg::return_envelope<Box>(p.geometry.outer()));
  return boxes;
}

// Insert, step 1: the scan and its band split at the tile lines (each piece
// of an edge keeps its type) and clipped to every tile their envelope meets.
// The tiles partition the plane, so the pieces' areas must add up to the
// whole: nullopt with the reason in `why` if they do not or a clip failed.
std::optional<std::vector<TilePiece>> clip_to_tiles(const PreparedScan& prepared, const TileGrid& grid,
                                                    const PolygonMapOptions& options, std::string& why) {
  TypedMultiPolygon scan{prepared.polygon};
  if (!options.assign_edge_types)
    for (auto& types : scan[0].edge_types) std::fill(types.begin(), types.end(), EdgeType::kFrontier);
  split_at_grid(scan[0], grid.size_m, grid.origin_m);
  MultiPolygon band_geometry = prepared.band;
  split_at_grid(band_geometry, grid.size_m, grid.origin_m);
  const TypedMultiPolygon band = with_uniform_type(band_geometry, EdgeType::kObstacle);
  Box envelope = bg::return_envelope<Box>(prepared.polygon.geometry);
  if (!band.empty()) bg::expand(envelope, bg::return_envelope<Box>(band_geometry));
  const auto [first, last] = grid.range(envelope);
  const std::vector<Box> scan_boxes = envelopes_of(scan), band_boxes = envelopes_of(band);
  std::vector<TilePiece> pieces;
  double free_sum = 0.0, band_sum = 0.0;
  for (auto i = first.first; i <= last.first; ++i) {
    for (auto j = first.second; j <= last.second; ++j) {
      const TileKey key{i, j};
      const Box box = grid.box(key);
      auto free = clip_split_layer(scan, scan_boxes, box, op_options(options, box, false));
      auto clipped_band = clip_split_layer(band, band_boxes, box, op_options(options, box, true));
      if (!free.ok || !clipped_band.ok) {
        why = !free.ok ? free.error : clipped_band.error;
        return std::nullopt;
      }
      if (free.polygons.empty() && clipped_band.polygons.empty()) continue;
      free_sum += area(free.polygons);
      band_sum += area(clipped_band.polygons);
      pieces.push_back({key, box, std::move(free.polygons), std::move(clipped_band.polygons)});
    }
  }
  // The overlay moves the boundary by at most kOverlayMovesM, so an area by
  // at most the boundary's length (with the tile sides the clip adds) times
  // that (area_within, which measures the boundary only when the sum is off
  // by more than the plain rounding); a lost piece is far more.
  const double scan_area = area(scan), band_area = area(band);
  const double tile_sides_m = 4.0 * grid.size_m * static_cast<double>(pieces.size());
  if (area_within(free_sum, scan_area, scan_area, [&] { return bg::perimeter(scan[0].geometry) + tile_sides_m; }) &&
      area_within(band_sum, band_area, band_area, [&] { return bg::perimeter(band_geometry) + tile_sides_m; }))
    return pieces;
  why = "clipping to tiles does not conserve area (scan " + std::to_string(scan_area) + " vs " +
        std::to_string(free_sum) + " m2, band " + std::to_string(band_area) + " vs " + std::to_string(band_sum) +
        " m2)";
  return std::nullopt;
}

// Insert, step 2, for one layer of one tile: old ∪ piece, simplified and
// checked. A union's area lies between the larger input and the sum of both.
// Only what the union produced is simplified; the polygons it passed through
// unchanged are checked only where the produced ones come near them.
bool unite_layer(const TypedMultiPolygon* old, TypedMultiPolygon& piece, const TypedOpOptions& typed,
                 double epsilon_m, TypedMultiPolygon& out, double& area_after_union, InsertResult& result,
                 std::string& why) {
  if (!old || old->empty()) {
    out = std::move(piece);
    area_after_union = area(out);
    return simplify_and_check(out, out.size(), epsilon_m, why);
  }
  auto united = typed_union(*old, piece, typed);
  if (!united.ok) {
    why = united.error;
    return false;
  }
  const double a_old = area(*old), a_new = area(piece);
  area_after_union = area(united.polygons);
  if (!area_within(area_after_union, std::max(a_old, a_new), a_old + a_new, [&] {
        return bg::perimeter(geometry_of(*old)) + bg::perimeter(geometry_of(piece));
      })) {
    why = "union area out of bounds";
    return false;
  }
  if (!simplify_and_check(united.polygons, united.polygons.size() - united.unchanged_tail, epsilon_m, why))
    return false;
  result.reassign.edges += united.reassign.edges;
  result.reassign.candidates += united.reassign.candidates;
  out = std::move(united.polygons);
  return true;
}

using TileTable = std::map<TileKey, std::shared_ptr<const Tile>>;

// Insert, step 2: the tile's free layer ∪ the scan's piece and its obstacle
// layer ∪ the band's piece, as a new tile that replaces the old one. False
// (the tile keeps its old state) if either union fails.
bool update_tile(TileTable& tiles, TilePiece& piece, const PolygonMapOptions& options, InsertResult& result,
                 std::string& why) {
  ++result.tiles_touched;
  const auto found = tiles.find(piece.key);
  const Tile* old = found == tiles.end() ? nullptr : found->second.get();
  TypedMultiPolygon free, obstacles;
  double free_area = 0.0, band_area = 0.0;
  if (!unite_layer(old ? &old->free : nullptr, piece.free, op_options(options, piece.box, false),
                   options.simplify_epsilon_m, free, free_area, result, why)) {
    why = "free: " + why;
    return false;
  }
  if (!unite_layer(old ? &old->obstacles : nullptr, piece.band, op_options(options, piece.box, true),
                   options.simplify_epsilon_m, obstacles, band_area, result, why)) {
    why = "obstacles: " + why;
    return false;
  }
  result.free_area_before_m2 += old ? area(old->free) : 0.0;
  result.free_area_after_union_m2 += free_area;
  const Tile::PlanningOptions planning{options.simplify_epsilon_m, options.assign_edge_types};
  tiles[piece.key] = std::make_shared<const Tile>(piece.box, std::move(free), std::move(obstacles),
                                                  old ? old->last_good_planning() : nullptr, planning);
  return true;
}

// What a merge unites: per tile, its polygons with an edge on the tile's
// border (the only ones that can meet another tile's); the others, which lie
// inside their tile and pass through; and, if `set_holes_aside`, the holes
// strictly inside their tile's box, left out of the overlay and put back,
// with the polygons inside their boxes (islands in them), which meet nothing
// the merge changes.
struct MergeParts {
  std::vector<TypedMultiPolygon> parts;
  TypedMultiPolygon inside;
  std::vector<TypedRing> aside;
  TypedMultiPolygon in_aside_holes;
};

// Merge, step 1.
template <class LayerOf>
MergeParts collect_parts(const TileTable& tiles, LayerOf&& layer_of, bool set_holes_aside) {
  MergeParts m;
  for (const auto& [key, tile] : tiles) {
    const Box& box = tile->box;
    auto strictly_inside = [&box](const Ring& ring) {
      const Box e = bg::return_envelope<Box>(ring);
      return e.min_corner().x() > box.min_corner().x() && e.min_corner().y() > box.min_corner().y() &&
             e.max_corner().x() < box.max_corner().x() && e.max_corner().y() < box.max_corner().y();
    };
    TypedMultiPolygon touching, inside;
    const std::size_t first_aside = m.aside.size();
    for (const auto& polygon : layer_of(*tile)) {
      bool on_border = false;
      for (const auto& ring : polygon.edge_types)
        on_border = on_border || std::find(ring.begin(), ring.end(), EdgeType::kBorder) != ring.end();
      if (!on_border)
        inside.push_back(polygon);
      else if (set_holes_aside)
        touching.push_back(without_holes(polygon, strictly_inside, m.aside));
      else
        touching.push_back(polygon);
    }
    for (auto& polygon : inside) {
      const Box e = bg::return_envelope<Box>(polygon.geometry.outer());
      const bool in_hole = std::any_of(m.aside.begin() + static_cast<std::ptrdiff_t>(first_aside), m.aside.end(),
                                       [&e](const TypedRing& hole) { return bg::within(e, bg::return_envelope<Box>(hole.ring)); });
      (in_hole ? m.in_aside_holes : m.inside).push_back(std::move(polygon));
    }
    if (!touching.empty()) m.parts.push_back(std::move(touching));
  }
  return m;
}

// Merge, step 2: a balanced cascade of unions (each vertex takes part in
// O(log tiles) of them); border pieces of neighbouring tiles coincide in
// opposite directions and drop out. nullopt: an overlay failed.
std::optional<TypedMultiPolygon> unite_all(std::vector<TypedMultiPolygon> work) {
  while (work.size() > 1) {
    std::vector<TypedMultiPolygon> next;
    next.reserve((work.size() + 1) / 2);
    for (std::size_t k = 0; k + 1 < work.size(); k += 2) {
      auto u = overlay(work[k], work[k + 1], OverlayOp::kUnion);
      if (!u.ok) return std::nullopt;
      next.push_back(std::move(u.polygons));
    }
    if (work.size() % 2 == 1) next.push_back(std::move(work.back()));
    work = std::move(next);
  }
  return work.empty() ? TypedMultiPolygon{} : std::move(work.front());
}

// Merge, step 3: border edges left after the union (free space on one side
// only) become frontier; all edges do in a map without edge types. Returns
// how many border edges were left.
std::int64_t border_to_frontier(TypedMultiPolygon& polygons, bool assign_edge_types) {
  std::int64_t strays = 0;
  for (auto& p : polygons)
    for (auto& ring : p.edge_types)
      for (auto& t : ring) {
        strays += t == EdgeType::kBorder ? 1 : 0;
        if (t == EdgeType::kBorder || !assign_edge_types) t = EdgeType::kFrontier;
      }
  return strays;
}

// Merge, step 4: the vertices a tile line added to an edge (on the line,
// between two edges of one type, within 1e-9 m of the line through its
// neighbours, and a vertex of no other ring of `polygons` or `others`: a
// ring touching there would be left on the edge's interior) are dropped,
// so a merged edge is one edge again.
void drop_tile_line_vertices(TypedMultiPolygon& polygons, const TypedMultiPolygon& others, const TileGrid& grid) {
  auto on_line = [&grid](double v) { return grid.line(grid.index(v)) == v; };
  std::map<std::pair<double, double>, int> uses;  // tile-line vertices: how many ring corners
  auto count = [&](const TypedMultiPolygon& ps) {
    for_each_edge(ps, [&](const Point& a, const Point&, EdgeType) {
      if (on_line(a.x()) || on_line(a.y())) ++uses[{a.x(), a.y()}];
    });
  };
  count(polygons);
  count(others);
  auto drop = [&](Ring& ring, std::vector<EdgeType>& types) {
    const std::size_t n = types.size();
    Ring kept_ring;
    std::vector<EdgeType> kept_types;
    for (std::size_t i = 0; i < n; ++i) {
      const Point& u = ring[(i + n - 1) % n];
      const Point& v = ring[i];
      const Point& w = ring[i + 1];
      const double dx = w.x() - u.x(), dy = w.y() - u.y();
      const double off = dx * (v.y() - u.y()) - dy * (v.x() - u.x());
      const bool dissolve = (on_line(v.x()) || on_line(v.y())) && types[(i + n - 1) % n] == types[i] &&
                            off * off <= 1e-18 * (dx * dx + dy * dy) && n - (i - kept_types.size()) > 3 &&
                            uses[{v.x(), v.y()}] == 1;
      if (dissolve && i > 0) continue;
      kept_ring.push_back(v);
      kept_types.push_back(types[i]);
    }
    kept_ring.push_back(kept_ring.front());
    ring = std::move(kept_ring);
    types = std::move(kept_types);
  };
  for (auto& p : polygons) {
    drop(p.geometry.outer(), p.edge_types[0]);
    for (std::size_t k = 0; k < p.geometry.inners().size(); ++k) drop(p.geometry.inners()[k], p.edge_types[1 + k]);
  }
}

}  // namespace

PreparedScan prepare_scan(TypedPolygon scan, const PolygonMapOptions& options) {
  PreparedScan prepared;
  try {
    prepared.band = obstacle_band(scan, options.obstacle_inner_m, options.obstacle_outer_m, &prepared.band_error,
                                  options.obstacle_end_trim_m);
  } catch (const std::exception& e) {
    prepared.band_error = std::string("obstacle band failed: ") + e.what();
  }
  if (!prepared.band_error.empty()) prepared.band.clear();
  prepared.polygon = std::move(scan);
  return prepared;
}

PolygonMap::PolygonMap(PolygonMapOptions options)
    : options_(options), grid_{options.tile_size_m, options.tile_origin_m} {}

InsertResult PolygonMap::insert(const TypedPolygon& scan) { return insert(prepare_scan(scan, options_)); }

// Checks the scan, clips it and its band to the tiles (step 1), unites each
// piece with its tile (step 2) and replaces the tiles. A tile whose update
// fails keeps its old state; a scan that cannot be clipped is refused.
InsertResult PolygonMap::insert(const PreparedScan& prepared) {
  InsertResult result;
  result.ok = true;
  auto fail = [&](const std::string& why) {
    ++result.tiles_failed;
    ++failed_tile_updates_;
    if (result.ok) result.error = why;
    result.ok = false;
  };
  std::string why;
  if (!is_valid_cheap_first(prepared.polygon, &why)) {
    result.ok = false;
    result.error = "scan polygon invalid: " + why;
    return result;
  }
  if (!prepared.band_error.empty()) fail(prepared.band_error);
  auto pieces = clip_to_tiles(prepared, grid_, options_, why);
  if (!pieces) {
    fail(why);
    return result;
  }
  for (auto& piece : *pieces)
    if (!update_tile(tiles_, piece, options_, result, why)) fail(why);
  ++scans_inserted_;
  return result;
}

// Collects what can meet across tile borders (step 1), unites it (step 2),
// retypes the borders left (step 3), dissolves the tile lines' vertices
// (step 4), checks the result with the polygons inside tiles near it and
// puts back the holes set aside and the islands in them.
MergeResult PolygonMap::merge(Layer layer, double simplify_epsilon_m) const {
  MergeResult result;
  if (layer == Layer::kPlanning)
    for (const auto& [key, tile] : tiles_) result.stale_planning_tiles += tile->planning_failed() ? 1 : 0;
  // The tiles' polygons were simplified and checked with the tiles' own
  // tolerance: with it (or none) they need not be simplified again.
  const bool tiles_tolerance = simplify_epsilon_m == options_.simplify_epsilon_m || simplify_epsilon_m <= 0.0;
  MergeParts parts = collect_parts(
      tiles_, [layer](const Tile& tile) -> const TypedMultiPolygon& { return layer == Layer::kFree ? tile.free : tile.planning(); },
      tiles_tolerance);
  auto united = unite_all(std::move(parts.parts));
  if (!united) return {.error = "the edge overlay could not unite the tiles", .polygons = {}};
  TypedMultiPolygon merged = std::move(*united);
  result.stray_border_edges = border_to_frontier(merged, options_.assign_edge_types);
  if (!options_.assign_edge_types) border_to_frontier(parts.inside, false);
  // With the tiles' tolerance only the vertices the tile lines added go
  // (a change below 1e-9 m); the polygons inside tiles are kept as they are
  // and checked only near the merged ones. Another tolerance: all polygons
  // are simplified and checked.
  if (tiles_tolerance) drop_tile_line_vertices(merged, parts.inside, grid_);
  const std::size_t changed = tiles_tolerance ? merged.size() : merged.size() + parts.inside.size();
  merged.insert(merged.end(), std::make_move_iterator(parts.inside.begin()),
                std::make_move_iterator(parts.inside.end()));
  std::string why;
  if (!simplify_and_check(merged, changed, tiles_tolerance ? 0.0 : simplify_epsilon_m, why))
    return {.error = "merged map invalid: " + why, .polygons = {}};
  // The holes set aside and the islands in them lie strictly inside their
  // tile's box, where the merged map is the tile's own polygon, unchanged:
  // they sit in it as they sat in the tile.
  if (!put_back_holes(merged, std::move(parts.aside)))
    return {.error = "a hole set aside has no polygon to return to", .polygons = {}};
  merged.insert(merged.end(), std::make_move_iterator(parts.in_aside_holes.begin()),
                std::make_move_iterator(parts.in_aside_holes.end()));
  result.polygons = std::move(merged);
  result.ok = true;
  return result;
}

void PolygonMap::restore_tile(const TileKey& key, TypedMultiPolygon free, TypedMultiPolygon obstacles) {
  const Tile::PlanningOptions planning_options{options_.simplify_epsilon_m, options_.assign_edge_types};
  tiles_[key] = std::make_shared<const Tile>(grid_.box(key), std::move(free), std::move(obstacles), nullptr,
                                             planning_options);
}

void PolygonMap::restore_counters(std::int64_t scans_inserted, std::int64_t failed_tile_updates) {
  scans_inserted_ = scans_inserted;
  failed_tile_updates_ = failed_tile_updates;
}

MergeResult PolygonMap::free_space(std::optional<double> simplify_epsilon_m) const {
  return merge(Layer::kFree, simplify_epsilon_m.value_or(options_.simplify_epsilon_m));
}
MergeResult PolygonMap::planning_map(std::optional<double> simplify_epsilon_m) const {
  return merge(Layer::kPlanning, simplify_epsilon_m.value_or(options_.simplify_epsilon_m));
}

std::size_t PolygonMap::free_vertex_count() const {
  std::size_t n = 0;
  for (const auto& [key, tile] : tiles_) n += vertex_count(tile->free);
  return n;
}

std::size_t PolygonMap::planning_vertex_count() const {
  std::size_t n = 0;
  for (const auto& [key, tile] : tiles_) n += vertex_count(tile->planning());
  return n;
}

double PolygonMap::free_area_m2() const {
  double a = 0.0;
  for (const auto& [key, tile] : tiles_) a += area(tile->free);
  return a;
}

std::size_t PolygonMap::memory_bytes() const {
  std::size_t bytes = 0;
  for (const auto& [key, tile] : tiles_) bytes += 64 + tile->memory_bytes();  // + map node and control block
  return bytes;
}

}  // namespace pex::mapping
