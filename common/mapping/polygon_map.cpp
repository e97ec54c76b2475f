// Boost.Geometry 1.74 buffer/rescale code trips -Wmaybe-uninitialized when
// inlined into our code; the warning is in Boost, not here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "mapping/polygon_map.hpp"

#include <algorithm>
#include <cmath>

namespace pex::mapping {

namespace {

namespace bs = bg::strategy::buffer;

constexpr double kGridSnap = 1e-9;

// The one expression for a grid line, so every caller gets the same bits.
double grid_line(std::int64_t k, double cell, double origin) {
  return origin + static_cast<double>(k) * cell;
}
std::int64_t grid_index(double v, double cell, double origin) {
  return static_cast<std::int64_t>(std::floor((v - origin) / cell));
}

// Points where segment p-q crosses grid lines, ordered from p to q.
void grid_crossings(const Point& p, const Point& q, double cell, double origin,
                    std::vector<Point>& out) {
  out.clear();
  // Canonical order, so both traversal directions compute the same bits.
  const bool swap = (q.x() < p.x()) || (q.x() == p.x() && q.y() < p.y());
  const Point a = swap ? q : p, b = swap ? p : q;
  std::vector<std::pair<double, Point>> hits;
  auto snap = [&](double v) {
    const auto k = static_cast<std::int64_t>(std::round((v - origin) / cell));
    const double g = grid_line(k, cell, origin);
    return std::abs(v - g) <= kGridSnap ? g : v;
  };
  if (a.x() != b.x()) {
    const auto k0 = grid_index(a.x(), cell, origin);
    for (auto k = k0; grid_line(k, cell, origin) < b.x(); ++k) {
      const double x = grid_line(k, cell, origin);
      if (x <= a.x()) continue;
      const double t = (x - a.x()) / (b.x() - a.x());
      hits.push_back({t, Point(x, snap(a.y() + t * (b.y() - a.y())))});
    }
  }
  const double ylo = std::min(a.y(), b.y()), yhi = std::max(a.y(), b.y());
  if (ylo != yhi) {
    const auto k0 = grid_index(ylo, cell, origin);
    for (auto k = k0; grid_line(k, cell, origin) < yhi; ++k) {
      const double y = grid_line(k, cell, origin);
      if (y <= ylo) continue;
      const double t = (y - a.y()) / (b.y() - a.y());
      hits.push_back({t, Point(snap(a.x() + t * (b.x() - a.x())), y)});
    }
  }
  std::sort(hits.begin(), hits.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  for (const auto& h : hits) {
    if (!out.empty() && bg::distance(out.back(), h.second) < kGridSnap) continue;
    if (bg::distance(h.second, a) < kGridSnap || bg::distance(h.second, b) < kGridSnap) continue;
    out.push_back(h.second);
  }
  if (swap) std::reverse(out.begin(), out.end());
}

// Splits ring's edges at grid lines; `types`, if given, is split alongside
// (each piece keeps its edge's type).
void split_ring(Ring& ring, std::vector<EdgeType>* types, double cell, double origin) {
  if (ring.size() < 2) return;
  Ring out;
  out.reserve(ring.size());
  std::vector<EdgeType> out_types;
  if (types) out_types.reserve(types->size());
  std::vector<Point> crossings;
  for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
    out.push_back(ring[i]);
    grid_crossings(ring[i], ring[i + 1], cell, origin, crossings);
    out.insert(out.end(), crossings.begin(), crossings.end());
    if (types) out_types.insert(out_types.end(), 1 + crossings.size(), (*types)[i]);
  }
  out.push_back(ring.back());
  ring = std::move(out);
  if (types) *types = std::move(out_types);
}

// The cheap sufficient test first; Boost decides what it cannot show (rings
// touching at points, near-degenerate geometry) and says why when invalid.
bool valid_layer(const TypedMultiPolygon& layer, std::string& why) {
  return is_clearly_valid(layer) || bg::is_valid(geometry_of(layer), why);
}

// RDP then one validity check of the whole layer. If RDP made the layer
// invalid (rare), RDP again polygon by polygon, keeping each polygon it would
// break, and check once more; then the unsimplified layer. False if none is valid.
bool simplify_and_validate(TypedMultiPolygon& layer, double epsilon_m, std::string& why) {
  if (epsilon_m > 0.0) {
    for (const bool check_each_polygon : {false, true}) {
      TypedMultiPolygon simplified = simplify_typed(layer, epsilon_m, check_each_polygon);
      if (valid_layer(simplified, why)) {
        layer = std::move(simplified);
        return true;
      }
    }
  }
  return valid_layer(layer, why);
}

// The same for all but the last `unchanged_tail` polygons, which are kept as
// they are (simplified and checked when they were made).
bool simplify_and_validate(TypedMultiPolygon& layer, std::size_t unchanged_tail, double epsilon_m,
                           std::string& why) {
  if (unchanged_tail == 0) return simplify_and_validate(layer, epsilon_m, why);
  const auto split = layer.end() - static_cast<std::ptrdiff_t>(unchanged_tail);
  TypedMultiPolygon changed(std::make_move_iterator(layer.begin()), std::make_move_iterator(split));
  if (!changed.empty() && !simplify_and_validate(changed, epsilon_m, why)) return false;
  changed.insert(changed.end(), std::make_move_iterator(split), std::make_move_iterator(layer.end()));
  layer = std::move(changed);
  return true;
}

// Points within kGridSnap of the point before them, but for the closing point.
void drop_repeated_points(Ring& ring) {
  if (ring.size() < 3) return;
  Ring out;
  out.reserve(ring.size());
  for (std::size_t i = 0; i + 1 < ring.size(); ++i)
    if (out.empty() || bg::distance(out.back(), ring[i]) > kGridSnap) out.push_back(ring[i]);
  while (out.size() > 1 && bg::distance(out.back(), out.front()) <= kGridSnap) out.pop_back();
  out.push_back(out.front());
  ring = std::move(out);
}

}  // namespace

void split_at_grid(MultiPolygon& geometry, double cell_m, double origin_m) {
  for (auto& polygon : geometry) {
    split_ring(polygon.outer(), nullptr, cell_m, origin_m);
    for (auto& inner : polygon.inners()) split_ring(inner, nullptr, cell_m, origin_m);
  }
}

void split_at_grid(TypedPolygon& polygon, double cell_m, double origin_m) {
  split_ring(polygon.geometry.outer(), &polygon.edge_types[0], cell_m, origin_m);
  for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
    split_ring(polygon.geometry.inners()[k], &polygon.edge_types[1 + k], cell_m, origin_m);
}

Chains obstacle_chains(const TypedPolygon& scan) {
  Chains chains;
  auto add_ring_chains = [&](const Ring& ring, const std::vector<EdgeType>& types) {
    const std::size_t n = types.size();
    if (n == 0) return;
    // Start right after a non-obstacle edge so no chain wraps around.
    std::size_t start = 0;
    while (start < n && types[start] == EdgeType::kObstacle) ++start;
    if (start == n) {  // a ring of obstacle edges only
      chains.emplace_back(ring.begin(), ring.end());
      return;
    }
    Chain chain;
    for (std::size_t j = 1; j <= n; ++j) {
      const std::size_t i = (start + j) % n;
      if (types[i] == EdgeType::kObstacle) {
        if (chain.empty()) chain.push_back(ring[i]);
        chain.push_back(ring[i + 1]);
      } else if (!chain.empty()) {
        chains.push_back(std::move(chain));
        chain.clear();
      }
    }
    if (!chain.empty()) chains.push_back(std::move(chain));
  };
  add_ring_chains(scan.geometry.outer(), scan.edge_types[0]);
  for (std::size_t k = 0; k < scan.geometry.inners().size(); ++k)
    add_ring_chains(scan.geometry.inners()[k], scan.edge_types[1 + k]);
  return chains;
}

namespace {

constexpr int kBandPointsPerCircle = 8;

// The offset of an open polyline `distance_m` to its right: round joins
// where the polyline turns left (the right side is convex there), the
// offset lines' meeting point where it turns right. Appends to `out`; false
// if a concave join's offset lines do not meet within both segments (a
// segment shorter than the offset: Boost's buffer handles that).
template <class It>
bool append_right_offset(It first, It last, double distance_m, Ring& out) {
  const auto n = static_cast<std::size_t>(std::distance(first, last));
  if (n < 2) return false;
  auto unit = [](const Point& a, const Point& b, double& length) {
    const double dx = b.x() - a.x(), dy = b.y() - a.y();
    length = std::hypot(dx, dy);
    return Point(dx / length, dy / length);
  };
  auto push = [&](const Point& p) {
    if (out.empty() || bg::distance(out.back(), p) > kGridSnap) out.push_back(p);
  };
  double length = 0.0;
  It a = first, b = std::next(first);
  Point d = unit(*a, *b, length);
  if (!(length > 0.0)) return false;
  push(Point(a->x() + d.y() * distance_m, a->y() - d.x() * distance_m));
  for (It c = std::next(b); c != last; ++a, ++b, ++c) {
    double next_length = 0.0;
    const Point e = unit(*b, *c, next_length);
    if (!(next_length > 0.0)) return false;
    const Point from(b->x() + d.y() * distance_m, b->y() - d.x() * distance_m);
    const Point to(b->x() + e.y() * distance_m, b->y() - e.x() * distance_m);
    const double turn = d.x() * e.y() - d.y() * e.x();
    if (turn > 1e-12) {  // left turn: an arc around b from `from` to `to`
      const double a0 = std::atan2(from.y() - b->y(), from.x() - b->x());
      double sweep = std::atan2(to.y() - b->y(), to.x() - b->x()) - a0;
      if (sweep < 0.0) sweep += 2.0 * M_PI;
      const int steps = static_cast<int>(std::ceil(sweep / (2.0 * M_PI / kBandPointsPerCircle)));
      push(from);
      for (int k = 1; k < steps; ++k) {
        const double angle = a0 + sweep * k / steps;
        push(Point(b->x() + distance_m * std::cos(angle), b->y() + distance_m * std::sin(angle)));
      }
      push(to);
    } else if (turn < -1e-12) {  // right turn: where the two offset lines meet
      const double t = ((to.x() - from.x()) * e.y() - (to.y() - from.y()) * e.x()) / turn;  // along d from `from`
      const double u = ((to.x() - from.x()) * d.y() - (to.y() - from.y()) * d.x()) / turn;  // along e from `to`
      if (t > 0.0 || -t > length || u < 0.0 || u > next_length) return false;
      push(Point(from.x() + t * d.x(), from.y() + t * d.y()));
    } else {
      push(from);
    }
    d = e;
    length = next_length;
  }
  push(Point(b->x() + d.y() * distance_m, b->y() - d.x() * distance_m));
  return true;
}

// The band of one open chain: its right offset by outer_m forward, then the
// right offset of the reversed chain (its left side) by inner_m, flat ends.
// Counter-clockwise. nullopt if a join cannot be built this way.
std::optional<Polygon> chain_band(const Chain& chain, double inner_m, double outer_m) {
  Polygon band;
  Ring& ring = band.outer();
  if (!append_right_offset(chain.begin(), chain.end(), outer_m, ring) ||
      !append_right_offset(chain.rbegin(), chain.rend(), inner_m, ring))
    return std::nullopt;
  while (ring.size() > 1 && bg::distance(ring.back(), ring.front()) <= kGridSnap) ring.pop_back();
  if (ring.size() < 3) return std::nullopt;
  ring.push_back(ring.front());
  return band;
}

}  // namespace

std::optional<MultiPolygon> direct_obstacle_band(const Chains& chains, double inner_m, double outer_m) {
  TypedMultiPolygon band;
  std::vector<Box> boxes;
  TypedOpOptions union_options;
  union_options.uniform_type = EdgeType::kObstacle;  // and validate: the union's result is checked
  for (const auto& chain : chains) {
    if (chain.size() < 2 || bg::equals(chain.front(), chain.back())) return std::nullopt;  // closed: a ring
    auto polygon = chain_band(chain, inner_m, outer_m);
    if (!polygon) return std::nullopt;
    TypedPolygon typed{std::move(*polygon), {}};
    typed.edge_types.push_back(std::vector<EdgeType>(typed.geometry.outer().size() - 1, EdgeType::kObstacle));
    if (!is_clearly_valid(std::span(&typed, 1))) return std::nullopt;  // the chain's band folds
    const Box box = bg::return_envelope<Box>(typed.geometry);
    const bool meets = std::any_of(boxes.begin(), boxes.end(), [&](const Box& b) { return !bg::disjoint(b, box); });
    if (!meets) {
      band.push_back(std::move(typed));
      boxes.push_back(box);
      continue;
    }
    // Chains closer than the band's width (a gap in a wall, a corner): their
    // bands overlap and are united.
    auto united = typed_union(band, {typed}, union_options);
    if (!united.ok) return std::nullopt;
    band = std::move(united.polygons);
    boxes.clear();
    for (const auto& p : band) boxes.push_back(bg::return_envelope<Box>(p.geometry));
  }
  if (!is_clearly_valid(band) && !bg::is_valid(geometry_of(band))) return std::nullopt;
  return geometry_of(band);
}

MultiPolygon obstacle_band(const TypedPolygon& scan, double inner_m, double outer_m, std::string* why) {
  const Chains chains = obstacle_chains(scan);
  MultiPolygon band;
  if (chains.empty()) return band;
  if (auto direct = direct_obstacle_band(chains, inner_m, outer_m)) return std::move(*direct);  // checked there
  // A closed chain, a chain whose band folds, a failed union: Boost's buffer.
  bg::buffer(chains, band, bs::distance_asymmetric<double>(inner_m, outer_m), bs::side_straight(),
             bs::join_round(kBandPointsPerCircle), bs::end_flat(), bs::point_circle(kBandPointsPerCircle));
  // It leaves repeated points where a side meets a flat end; without them
  // the band passes the cheap validity test.
  for (auto& polygon : band) {
    drop_repeated_points(polygon.outer());
    for (auto& inner : polygon.inners()) drop_repeated_points(inner);
  }
  std::string reason;
  if (!is_clearly_valid(with_uniform_type(band, EdgeType::kObstacle)) && !bg::is_valid(band, reason)) {
    if (why) *why = "obstacle band invalid: " + reason;
    band.clear();
  }
  return band;
}

Tile::Tile(Box box_in, TypedMultiPolygon free_in, TypedMultiPolygon obstacles_in,
           std::shared_ptr<const TypedMultiPolygon> last_good_planning, PlanningOptions options)
    : box(box_in),
      free(std::move(free_in)),
      obstacles(std::move(obstacles_in)),
      options_(options),
      fallback_(std::move(last_good_planning)) {}

const TypedMultiPolygon& Tile::planning() const {
  const std::lock_guard lock(mutex_);
  if (!planning_) compute_planning();
  return *planning_;  // never replaced once set, so the reference stays good
}

bool Tile::planning_computed() const {
  const std::lock_guard lock(mutex_);
  return planning_ != nullptr;
}

bool Tile::planning_failed() const {
  planning();
  const std::lock_guard lock(mutex_);
  return !error_.empty();
}

bool Tile::planning_by_boost() const {
  planning();
  const std::lock_guard lock(mutex_);
  return planning_by_boost_;
}

std::string Tile::planning_error() const {
  planning();
  const std::lock_guard lock(mutex_);
  return error_;
}

std::shared_ptr<const TypedMultiPolygon> Tile::last_good_planning() const {
  const std::lock_guard lock(mutex_);
  // Not computed yet: pass on this tile's own fallback rather than keep this
  // version alive (a chain of never-read versions would hold every old tile
  // of a particle's lineage).
  if (!planning_ || !error_.empty()) return fallback_;
  return planning_;
}

std::size_t Tile::memory_bytes() const {
  std::size_t bytes = sizeof(Tile) + mapping::memory_bytes(free) + mapping::memory_bytes(obstacles);
  const std::lock_guard lock(mutex_);
  if (planning_) bytes += mapping::memory_bytes(*planning_);
  else if (fallback_) bytes += mapping::memory_bytes(*fallback_);
  return bytes;
}

void Tile::compute_planning() const {
  auto fail = [this](std::string why) {
    error_ = std::move(why);
    planning_ = fallback_ ? fallback_ : std::make_shared<const TypedMultiPolygon>();
  };
  TypedMultiPolygon planning;
  if (obstacles.empty()) {
    planning = free;
    // Without obstacles every free edge is a frontier (borders stay).
    for (auto& p : planning)
      for (auto& ring : p.edge_types)
        for (auto& t : ring)
          if (t != EdgeType::kBorder) t = EdgeType::kFrontier;
  } else {
    TypedOpOptions typed;
    typed.assign_edge_types = options_.assign_edge_types;
    typed.validate = false;  // validated once below, after RDP
    typed.border_box = box;
    // Our edge overlay first; if its result fails a check, Boost's overlay.
    std::string why;
    for (const bool boost : {false, true}) {
      typed.boost_overlay = boost;
      auto difference = typed_difference(free, obstacles, EdgeType::kFrontier, EdgeType::kObstacle, typed);
      const bool can_retry = !boost && difference.boost_fallbacks == 0;
      if (!difference.ok) {
        why = difference.error;
      } else {
        // A difference lies between (free - obstacles) and free.
        const double a_free = area(free), a_diff = area(difference.polygons);
        if (a_diff > a_free + 1e-6 || a_diff < a_free - area(obstacles) - 1e-6) {
          why = "difference area out of bounds";
        } else if (!simplify_and_validate(difference.polygons, options_.simplify_epsilon_m, why)) {
          why = "planning layer invalid: " + why;
        } else {
          planning = std::move(difference.polygons);
          planning_by_boost_ = boost || difference.boost_fallbacks > 0;
          why.clear();
          break;
        }
      }
      if (!can_retry) break;
    }
    if (!why.empty()) fail(why);
  }
  if (error_.empty()) {
    planning_ = std::make_shared<const TypedMultiPolygon>(std::move(planning));
    fallback_.reset();  // superseded
  }
}

PreparedScan prepare_scan(TypedPolygon scan, const PolygonMapOptions& options) {
  PreparedScan prepared;
  try {
    prepared.band = obstacle_band(scan, options.obstacle_inner_m, options.obstacle_outer_m, &prepared.band_error);
  } catch (const std::exception& e) {
    prepared.band_error = std::string("obstacle band failed: ") + e.what();
  }
  if (!prepared.band_error.empty()) prepared.band.clear();
  prepared.polygon = std::move(scan);
  return prepared;
}

PolygonMap::PolygonMap(PolygonMapOptions options) : options_(options) {}

Box PolygonMap::tile_box(const TileKey& key) const {
  const double s = options_.tile_size_m, o = options_.tile_origin_m;
  return Box(Point(grid_line(key.first, s, o), grid_line(key.second, s, o)),
             Point(grid_line(key.first + 1, s, o), grid_line(key.second + 1, s, o)));
}

InsertResult PolygonMap::insert(const TypedPolygon& scan) { return insert(prepare_scan(scan, options_)); }

InsertResult PolygonMap::insert(const PreparedScan& prepared) {
  const TypedPolygon& scan = prepared.polygon;
  InsertResult result;
  result.ok = true;
  auto fail_tile = [&](const std::string& why) {
    ++result.tiles_failed;
    ++failed_tile_updates_;
    if (result.ok) result.error = why;
    result.ok = false;
  };
  std::string why;
  if (!(types_match_rings(scan) && is_clearly_valid(std::span(&scan, 1))) && !is_valid(scan, &why)) {
    result.ok = false;
    result.error = "scan polygon invalid: " + why;
    return result;
  }
  const double s = options_.tile_size_m;
  // The scan split at tile lines; each piece of an edge keeps the edge's type
  // (all frontier for a map without edge types).
  TypedMultiPolygon scan_split{scan};
  if (!options_.assign_edge_types)
    for (auto& types : scan_split[0].edge_types) std::fill(types.begin(), types.end(), EdgeType::kFrontier);
  split_at_grid(scan_split[0], s, options_.tile_origin_m);
  if (!prepared.band_error.empty()) fail_tile(prepared.band_error);
  MultiPolygon band = prepared.band;
  split_at_grid(band, s, options_.tile_origin_m);
  TypedOpOptions typed;
  typed.assign_edge_types = options_.assign_edge_types;
  typed.validate = false;  // each tile is validated once, at the end
  const TypedMultiPolygon band_typed = with_uniform_type(band, EdgeType::kObstacle);

  Box envelope;
  bg::envelope(scan.geometry, envelope);
  if (!band.empty()) bg::expand(envelope, bg::return_envelope<Box>(band));
  const double o = options_.tile_origin_m;
  const auto i0 = static_cast<std::int32_t>(grid_index(envelope.min_corner().x(), s, o));
  const auto i1 = static_cast<std::int32_t>(grid_index(envelope.max_corner().x(), s, o));
  const auto j0 = static_cast<std::int32_t>(grid_index(envelope.min_corner().y(), s, o));
  const auto j1 = static_cast<std::int32_t>(grid_index(envelope.max_corner().y(), s, o));

  // Phase 1: clip the scan and its band to every tile it meets. The tiles
  // partition the plane, so the pieces' areas must add up to the whole: this
  // catches overlay failures on degenerate contacts (Boost, touching a tile
  // only at its corner, has given the whole box back). If our edge overlay's
  // pieces do not add up, Boost's overlay clips again; a scan whose pieces
  // still do not add up is refused and the map stays as it was.
  struct Piece {
    TileKey key;
    Box box;
    TypedMultiPolygon free;
    TypedMultiPolygon band;
  };
  std::vector<Piece> pieces;
  const double scan_area = bg::area(scan.geometry), band_area = bg::area(band);
  for (const bool boost : {false, true}) {
    pieces.clear();
    double free_sum = 0.0, band_sum = 0.0;
    int fallbacks = 0;
    for (auto i = i0; i <= i1; ++i) {
      for (auto j = j0; j <= j1; ++j) {
        const TileKey key{i, j};
        const Box box = tile_box(key);
        TypedOpOptions tile_options = typed;
        tile_options.border_box = box;
        tile_options.boost_overlay = boost;
        auto clip_free = typed_clip(scan_split, box, tile_options);
        TypedOpOptions band_options = tile_options;
        band_options.uniform_type = EdgeType::kObstacle;
        TypedOpResult clip_band{true, {}, {}, {}, 0, 0};
        if (!band_typed.empty()) clip_band = typed_clip(band_typed, box, band_options);
        fallbacks += clip_free.boost_fallbacks + clip_band.boost_fallbacks;
        if (!clip_free.ok || !clip_band.ok) {
          result.ok = false;
          result.error = !clip_free.ok ? clip_free.error : clip_band.error;
          ++failed_tile_updates_;
          ++result.tiles_failed;
          return result;
        }
        if (clip_free.polygons.empty() && clip_band.polygons.empty()) continue;
        free_sum += area(clip_free.polygons);
        band_sum += area(clip_band.polygons);
        pieces.push_back({key, box, std::move(clip_free.polygons), std::move(clip_band.polygons)});
      }
    }
    result.boost_fallbacks += fallbacks;
    if (std::abs(free_sum - scan_area) <= 1e-6 * std::max(1.0, scan_area) &&
        std::abs(band_sum - band_area) <= 1e-6 * std::max(1.0, band_area))
      break;
    if (!boost) {
      ++result.boost_fallbacks;
      continue;
    }
    result.ok = false;
    result.error = "clipping to tiles does not conserve area (scan " + std::to_string(scan_area) + " vs " +
                   std::to_string(free_sum) + " m2, band " + std::to_string(band_area) + " vs " +
                   std::to_string(band_sum) + " m2)";
    ++failed_tile_updates_;
    ++result.tiles_failed;
    return result;
  }

  // Phase 2: update the tiles, each from its pieces.
  const Tile::PlanningOptions planning_options{options_.simplify_epsilon_m, options_.assign_edge_types};
  for (auto& piece : pieces) {
    {  // (one tile)
      const TileKey& key = piece.key;
      const Box& box = piece.box;
      TypedOpOptions tile_options = typed;
      tile_options.border_box = box;
      TypedOpOptions band_options = tile_options;
      band_options.uniform_type = EdgeType::kObstacle;
      ++result.tiles_touched;

      const auto found = tiles_.find(key);
      const Tile* old = found == tiles_.end() ? nullptr : found->second.get();
      // One layer: old ∪ piece, simplified and checked. Returns false (tile
      // failed) on an error, an area out of bounds or an invalid result. If
      // our edge overlay made the result that failed, Boost's overlay gets a
      // second try.
      auto update_layer = [&](const TypedMultiPolygon* old_layer, TypedMultiPolygon& piece_layer,
                              TypedOpOptions op_options, const char* what, TypedMultiPolygon& out,
                              double* area_after_union) {
        if (!old_layer || old_layer->empty()) {
          out = std::move(piece_layer);
          if (area_after_union) *area_after_union = area(out);
          if (simplify_and_validate(out, options_.simplify_epsilon_m, why)) return true;
          fail_tile(std::string(what) + " invalid: " + why);
          return false;
        }
        for (const bool boost : {false, true}) {
          op_options.boost_overlay = boost;
          auto merged = typed_union(*old_layer, piece_layer, op_options);
          result.boost_fallbacks += merged.boost_fallbacks;
          const bool can_retry = !boost && merged.boost_fallbacks == 0;
          auto retry_or_fail = [&](const std::string& why_failed) {
            if (can_retry) {
              ++result.boost_fallbacks;
              return false;
            }
            fail_tile(std::string(what) + ": " + why_failed);
            return true;
          };
          if (!merged.ok) {
            if (retry_or_fail(merged.error)) return false;
            continue;
          }
          // A union lies between the larger input and the sum of both.
          const double a_old = area(*old_layer), a_new = area(piece_layer), a_union = area(merged.polygons);
          if (a_union < std::max(a_old, a_new) - 1e-6 || a_union > a_old + a_new + 1e-6) {
            if (retry_or_fail("union area out of bounds")) return false;
            continue;
          }
          // Only what the union produced is simplified and checked: the
          // polygons it passed through were valid in the old tile, and their
          // boxes meet no new piece, so they stay disjoint from the rest.
          if (!simplify_and_validate(merged.polygons, merged.unchanged_tail, options_.simplify_epsilon_m, why)) {
            if (retry_or_fail("invalid after union: " + why)) return false;
            continue;
          }
          result.reassign.edges += merged.reassign.edges;
          result.reassign.candidates += merged.reassign.candidates;
          out = std::move(merged.polygons);
          if (area_after_union) *area_after_union = a_union;
          return true;
        }
        return false;
      };
      TypedMultiPolygon free, obstacles;
      double area_after_union = 0.0;
      if (!update_layer(old ? &old->free : nullptr, piece.free, tile_options, "free", free, &area_after_union) ||
          !update_layer(old ? &old->obstacles : nullptr, piece.band, band_options, "obstacles", obstacles, nullptr))
        continue;
      const double area_before = old ? area(old->free) : 0.0;
      result.free_area_before_m2 += area_before;
      result.free_area_after_union_m2 += area_after_union;
      tiles_[key] = std::make_shared<const Tile>(box, std::move(free), std::move(obstacles),
                                                 old ? old->last_good_planning() : nullptr, planning_options);
    }
  }
  ++scans_inserted_;
  boost_fallbacks_ += result.boost_fallbacks;
  return result;
}

void PolygonMap::restore_tile(const TileKey& key, TypedMultiPolygon free, TypedMultiPolygon obstacles) {
  const Tile::PlanningOptions planning_options{options_.simplify_epsilon_m, options_.assign_edge_types};
  tiles_[key] = std::make_shared<const Tile>(tile_box(key), std::move(free), std::move(obstacles), nullptr,
                                             planning_options);
}

void PolygonMap::restore_counters(std::int64_t scans_inserted, std::int64_t failed_tile_updates,
                                  std::int64_t boost_fallbacks) {
  scans_inserted_ = scans_inserted;
  failed_tile_updates_ = failed_tile_updates;
  boost_fallbacks_ = boost_fallbacks;
}

MergeResult PolygonMap::merge(Layer layer, double simplify_epsilon_m) const {
  MergeResult result;
  auto polygons_of = [layer](const Tile& tile) -> const TypedMultiPolygon& {
    return layer == Layer::kFree ? tile.free : tile.planning();
  };
  if (layer == Layer::kPlanning)
    for (const auto& [key, tile] : tiles_) {
      result.stale_planning_tiles += tile->planning_failed() ? 1 : 0;
      result.boost_planning_tiles += tile->planning_by_boost() ? 1 : 0;
    }
  // Balanced cascade: each vertex takes part in O(log tiles) unions. With
  // our edge overlay the types come along; with Boost's (the fallback) they
  // are matched afterwards. nullopt: an overlay failed.
  auto cascade = [](std::vector<TypedMultiPolygon> work, bool boost) -> std::optional<TypedMultiPolygon> {
    while (work.size() > 1) {
      std::vector<TypedMultiPolygon> next;
      next.reserve((work.size() + 1) / 2);
      for (std::size_t k = 0; k + 1 < work.size(); k += 2) {
        if (boost) {
          MultiPolygon u;
          bg::union_(geometry_of(work[k]), geometry_of(work[k + 1]), u);
          next.push_back(with_uniform_type(u, EdgeType::kFrontier));  // typed at the end
          continue;
        }
        auto u = overlay(work[k], work[k + 1], OverlayOp::kUnion);
        if (!u.ok) return std::nullopt;
        next.push_back(std::move(u.polygons));
      }
      if (work.size() % 2 == 1) next.push_back(std::move(work.back()));
      work = std::move(next);
    }
    return work.empty() ? TypedMultiPolygon{} : std::move(work.front());
  };
  // Attempt 0 (our edge overlay) and 1 (Boost's): only polygons with an edge
  // on their tile's border are merged; the others lie inside their tile and
  // pass through (fast: most of the map). If that result is invalid, attempt
  // 2 merges everything with Boost, attempt 3 in reverse order (with Boost's
  // rescaling, which is off now, two polygons valid at tile scale could be
  // "invalid" at map scale).
  //
  // Holes strictly inside their tile's box cannot meet another tile's polygons
  // either: in attempts 0 and 1 they are set aside, the rest goes through the
  // cascade, and they are put back into the polygon that contains them after
  // the check. They were simplified and checked with their tile, so only when
  // this merge simplifies with the tiles' own tolerance (or not at all).
  std::string why;
  const bool tiles_tolerance =
      simplify_epsilon_m == options_.simplify_epsilon_m || simplify_epsilon_m <= 0.0;
  for (int attempt = 0; attempt < 4; ++attempt) {
    const bool boost = attempt > 0, everything = attempt > 1;
    std::vector<TypedMultiPolygon> parts;
    TypedMultiPolygon inside;
    std::vector<TypedRing> aside;
    for (const auto& [key, tile] : tiles_) {
      TypedMultiPolygon touching;
      const Box& box = tile->box;
      auto strictly_inside = [&box](const Ring& ring) {
        const Box e = bg::return_envelope<Box>(ring);
        return e.min_corner().x() > box.min_corner().x() && e.min_corner().y() > box.min_corner().y() &&
               e.max_corner().x() < box.max_corner().x() && e.max_corner().y() < box.max_corner().y();
      };
      for (const auto& polygon : polygons_of(*tile)) {
        bool on_border = everything;
        for (const auto& ring : polygon.edge_types)
          on_border = on_border || std::find(ring.begin(), ring.end(), EdgeType::kBorder) != ring.end();
        if (!on_border) {
          inside.push_back(polygon);
          continue;
        }
        if (everything || !tiles_tolerance) {
          touching.push_back(polygon);
          continue;
        }
        touching.push_back(without_holes(polygon, strictly_inside, aside));
      }
      if (!touching.empty()) parts.push_back(std::move(touching));
    }
    if (attempt == 3) std::reverse(parts.begin(), parts.end());
    EdgeTypeIndex index;  // Boost's cascade: its output typed from every input edge
    if (boost) {
      for (const auto& part : parts) index.add(part);
      index.build();
    }
    std::optional<TypedMultiPolygon> united;
    try {
      united = cascade(std::move(parts), boost);
    } catch (const std::exception& e) {
      why = e.what();
      continue;
    }
    if (!united) {
      why = "the edge overlay could not unite the tiles";
      continue;
    }
    TypedMultiPolygon merged;
    if (boost) {
      TypedOpOptions options;
      options.assign_edge_types = options_.assign_edge_types;
      merged = assign_types(geometry_of(*united), index, 1e-6, options, nullptr);
    } else {
      merged = std::move(*united);
      if (!options_.assign_edge_types)
        for (auto& p : merged)
          for (auto& ring : p.edge_types) std::fill(ring.begin(), ring.end(), EdgeType::kFrontier);
    }
    const std::size_t inside_count = inside.size();
    for (auto& polygon : inside) merged.push_back(std::move(polygon));
    std::int64_t strays = 0;
    for (auto& p : merged)
      for (auto& ring : p.edge_types)
        for (auto& t : ring)
          if (t == EdgeType::kBorder) {
            t = EdgeType::kFrontier;
            ++strays;
          }
    // One check of the whole result (after RDP, or without it if RDP broke
    // it), except the polygons that lie inside their tiles: those were
    // simplified and checked with their tile, and lie in their tile's box,
    // apart from everything else. With another RDP tolerance than the tiles'
    // they are simplified and checked like the rest.
    const std::size_t unchanged = simplify_epsilon_m == options_.simplify_epsilon_m ? inside_count : 0;
    if (!simplify_and_validate(merged, unchanged, simplify_epsilon_m, why)) continue;
    // The holes set aside: inside their tile's box, where the merged map is
    // the tile's own polygon, so they sit in it as they sat in the tile.
    if (!put_back_holes(merged, std::move(aside))) {
      why = "a hole set aside has no polygon to return to";
      continue;
    }
    result.polygons = std::move(merged);
    result.stray_border_edges = strays;
    result.boost_cascade = boost;
    result.ok = true;
    return result;
  }
  result.error = "merged map invalid: " + why;
  return result;
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
