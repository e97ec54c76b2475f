#include "mapping/tile.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include "mapping/typed_ops.hpp"

namespace pex::mapping {

namespace {

// How many times a changed polygon the cheap check cannot clear is
// simplified again, each time with a quarter of the tolerance before, the
// last time not at all. RDP can fold a small ring (a rock's hole whose
// short edge changes type turns into a bow-tie once its neighbours go) or
// bring it within the clearance of another; a finer tolerance keeps the
// vertices that held it apart. Without this, such a layer went to
// bg::is_valid, and a polygon refused there was stored unsimplified, its
// short pieces sending every later check of the tile to Boost again
// (docs/mapping.md, "Finer RDP where the check fails").
constexpr int kFinerSimplifications = 3;
// At most this many rounds of that per layer, whatever the number of changed
// polygons: a merge's layer of hundreds of polygons that touch at points
// (valid, but not clearly so) must not cost a check of the whole layer per
// polygon before bg::is_valid decides. One or two rounds clear a fold.
constexpr int kMaxFinerRounds = 6;

}  // namespace

bool simplify_and_check(TypedMultiPolygon& layer, std::size_t changed, double epsilon_m, std::string& why) {
  // The kept polygons that can meet the changed ones go right after them:
  // boxes overlap (RDP keeps a subset of the vertices, so a simplified
  // polygon stays in its box).
  std::vector<Box> boxes;
  boxes.reserve(changed);
  Box all;
  bg::assign_inverse(all);
  for (std::size_t k = 0; k < changed; ++k) {
    boxes.push_back(bg::return_envelope<Box>(layer[k].geometry.outer()));
    bg::expand(all, boxes.back());
  }
  const auto first_kept = layer.begin() + static_cast<std::ptrdiff_t>(changed);
  const auto last_neighbour =
      changed == 0 ? first_kept : std::partition(first_kept, layer.end(), [&](const TypedPolygon& p) {
        const Box box = bg::return_envelope<Box>(p.geometry.outer());
        return !bg::disjoint(box, all) &&
               std::any_of(boxes.begin(), boxes.end(), [&](const Box& b) { return !bg::disjoint(b, box); });
      });
  const std::span<const TypedPolygon> checked(layer.data(), static_cast<std::size_t>(last_neighbour - layer.begin()));
  if (epsilon_m <= 0.0 || changed == 0) return is_valid_cheap_first(checked, why);
  // Swapped: the layer gets the simplified polygons (one for each), and
  // `original` what came, without a copy.
  TypedMultiPolygon original = simplify_typed(std::span(layer.data(), changed), epsilon_m, false);
  std::swap_ranges(original.begin(), original.end(), layer.begin());
  std::vector<int> finer(changed, 0);  // how often each changed polygon was simplified again
  for (int round = 0;; ++round) {
    UnclearPolygons unclear;
    if (is_clearly_valid(checked, &unclear)) return true;
    if (round == kMaxFinerRounds) break;
    const std::size_t named[2] = {unclear.first, unclear.second};
    bool again = false;
    for (std::size_t i = 0; i < (named[0] == named[1] ? 1u : 2u); ++i) {
      const std::size_t k = named[i];
      if (k >= changed || finer[k] == kFinerSimplifications) continue;  // a kept one is not ours to change
      const double epsilon = ++finer[k] < kFinerSimplifications ? epsilon_m / (1 << (2 * finer[k])) : 0.0;
      layer[k] = epsilon > 0.0 ? std::move(simplify_typed(std::span(&original[k], 1), epsilon, false).front())
                               : original[k];
      again = true;
    }
    if (!again) break;
  }
  // What the cheap check cannot clear (rings touching at a point, features
  // near Boost's tolerance, a kept neighbour's own) bg::is_valid decides.
  if (is_valid_cheap_first(checked, why)) return true;
  TypedMultiPolygon simplified = simplify_typed(original, epsilon_m, true);  // each polygon kept valid
  std::move(simplified.begin(), simplified.end(), layer.begin());
  if (is_valid_cheap_first(checked, why)) return true;
  std::move(original.begin(), original.end(), layer.begin());
  return is_valid_cheap_first(checked, why);
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
    typed.validate = false;  // checked once below, after RDP
    typed.border_box = box;
    auto difference = typed_difference(free, obstacles, EdgeType::kFrontier, EdgeType::kObstacle, typed);
    std::string why = difference.error;
    if (difference.ok) {
      // A difference lies between (free - obstacles) and free.
      const double a_free = area(free), a_diff = area(difference.polygons);
      if (!area_within(a_diff, a_free - area(obstacles), a_free, [&] {
            return bg::perimeter(geometry_of(free)) + bg::perimeter(geometry_of(obstacles));
          }))
        why = "difference area out of bounds";
      else if (!simplify_and_check(difference.polygons, difference.polygons.size(), options_.simplify_epsilon_m, why))
        why = "planning layer invalid: " + why;
      else
        why.clear();
    }
    if (!why.empty()) {
      error_ = std::move(why);
      planning_ = fallback_ ? fallback_ : std::make_shared<const TypedMultiPolygon>();
      return;
    }
    planning = std::move(difference.polygons);
  }
  planning_ = std::make_shared<const TypedMultiPolygon>(std::move(planning));
  fallback_.reset();  // superseded
}

}  // namespace pex::mapping
