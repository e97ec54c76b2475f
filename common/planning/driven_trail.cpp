#include "planning/driven_trail.hpp"

#include <algorithm>
#include <cmath>

#include "archive/byte_archive.hpp"
#include "planning/inward_offset.hpp"

namespace pex::planning {

// One point of a trail and the trail before it: a child shares its parent's
// nodes, so resampling copies pointers, not points.
struct DrivenTrails::Node {
  mapping::Point point;
  // Mutable only so that the destructor can unlink a chain it owns alone.
  mutable std::shared_ptr<const Node> before;

  Node(mapping::Point p, std::shared_ptr<const Node> b) : point(p), before(std::move(b)) {}
  // Released node by node: a trail of many thousand points destroyed by
  // recursion through its shared pointers would run out of stack.
  ~Node() {
    std::shared_ptr<const Node> next = std::move(before);
    while (next && next.use_count() == 1) {
      std::shared_ptr<const Node> after = std::move(next->before);
      next = std::move(after);
    }
  }
};

DrivenTrails::DrivenTrails(DrivenTrailOptions options) : options_(options) {}
DrivenTrails::~DrivenTrails() = default;
DrivenTrails::DrivenTrails(DrivenTrails&&) noexcept = default;
DrivenTrails& DrivenTrails::operator=(DrivenTrails&&) noexcept = default;

DrivenTrails::Result DrivenTrails::update(const TrailUpdate& update) {
  Result result;
  const auto n = update.particles.size();
  if (n == 0 || n > static_cast<std::size_t>(options_.max_particles)) {
    result.error = "an update has " + std::to_string(n) + " particles (1.." +
                   std::to_string(options_.max_particles) + " expected)";
    return result;
  }
  if (update.best < 0 || static_cast<std::size_t>(update.best) >= n) {
    result.error = "best particle " + std::to_string(update.best) + " out of range";
    return result;
  }
  for (const auto& p : update.particles)
    if (!std::isfinite(p.pose.x_m) || !std::isfinite(p.pose.y_m) || !std::isfinite(p.pose.theta_rad)) {
      result.error = "a particle's pose is not finite";
      return result;
    }

  const Generation* last = generations_.empty() ? nullptr : &generations_.back();
  const bool same_epoch = epoch_ && *epoch_ == update.epoch;
  // A restored trail stands in for particles it does not know: no parent
  // index refers to it.
  const bool continues = last && !last->stand_in && same_epoch &&
                         update.generation == last->generation + (update.republished ? 0 : 1);
  if (continues) {
    for (const auto& p : update.particles)
      if (p.parent < 0 || static_cast<std::size_t>(p.parent) >= last->heads.size()) {
        result.error = "a parent index " + std::to_string(p.parent) + " out of range";
        return result;
      }
  }
  // Where each particle's trail goes on from.
  std::vector<std::shared_ptr<const Node>> from(n);
  if (continues) {
    for (std::size_t i = 0; i < n; ++i) from[i] = last->heads[static_cast<std::size_t>(update.particles[i].parent)];
  } else if (last && same_epoch) {
    // The parents index an update not seen here: the best trail held stands
    // in for every particle's (as the mapper's best map does for the maps).
    const auto best = last->heads[static_cast<std::size_t>(last->best)];
    std::fill(from.begin(), from.end(), best);
    result.resynced = true;
    // The generations held belong to the lineage before the break (a SLAM
    // restored from an older checkpoint counts them again): none is this one's.
    generations_.clear();
    last = nullptr;
  } else {
    result.new_epoch = last != nullptr;
    generations_.clear();  // another frame, or the first update: start afresh
  }

  Generation next;
  next.generation = update.generation;
  next.best = update.best;
  next.heads.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const mapping::Point p(update.particles[i].pose.x_m, update.particles[i].pose.y_m);
    const auto& head = from[i];
    const bool moved = !head || std::hypot(p.x() - head->point.x(), p.y() - head->point.y()) >= options_.min_spacing_m;
    next.heads[i] = moved ? std::make_shared<const Node>(p, head) : head;
  }
  // A republish repeats its generation: it replaces it.
  if (!generations_.empty() && generations_.back().generation == next.generation) generations_.pop_back();
  generations_.push_back(std::move(next));
  const auto kept = static_cast<std::size_t>(std::max(1, options_.kept_generations));
  if (generations_.size() > kept) generations_.erase(generations_.begin(), generations_.end() - static_cast<long>(kept));
  epoch_ = update.epoch;
  result.ok = true;
  return result;
}

std::vector<mapping::Point> DrivenTrails::flatten(const std::shared_ptr<const Node>& head) const {
  std::vector<mapping::Point> points;
  for (const Node* node = head.get(); node && points.size() < options_.max_points; node = node->before.get())
    points.push_back(node->point);
  std::reverse(points.begin(), points.end());
  return points;
}

std::optional<std::vector<mapping::Point>> DrivenTrails::trail(std::int64_t generation, int particle) const {
  const auto it = std::find_if(generations_.rbegin(), generations_.rend(),
                               [&](const Generation& g) { return g.generation == generation; });
  if (it == generations_.rend() || particle < 0) return std::nullopt;
  if (it->stand_in) return flatten(it->heads[static_cast<std::size_t>(it->best)]);
  if (static_cast<std::size_t>(particle) >= it->heads.size()) return std::nullopt;
  return flatten(it->heads[static_cast<std::size_t>(particle)]);
}

std::vector<mapping::Point> DrivenTrails::best_trail() const {
  if (generations_.empty()) return {};
  const auto& g = generations_.back();
  return flatten(g.heads[static_cast<std::size_t>(g.best)]);
}

std::optional<std::int64_t> DrivenTrails::newest_generation() const {
  if (generations_.empty()) return std::nullopt;
  return generations_.back().generation;
}

namespace {
constexpr char kTrailsMagic[] = "PEXTRAIL";
constexpr std::uint32_t kTrailsVersion = 1;
}  // namespace

std::string DrivenTrails::checkpoint() const {
  if (!epoch_ || generations_.empty()) return {};
  const auto& g = generations_.back();
  const auto points = flatten(g.heads[static_cast<std::size_t>(g.best)]);
  archive::ByteWriter w;
  w.put<std::int64_t>(*epoch_);
  w.put<std::int64_t>(g.generation);
  w.put<std::uint64_t>(points.size());
  for (const auto& p : points) {
    w.put<double>(p.x());
    w.put<double>(p.y());
  }
  return archive::seal(kTrailsMagic, kTrailsVersion, w.bytes());
}

std::string DrivenTrails::restore(std::string_view checkpoint) {
  Generation restored;
  std::int64_t epoch = 0;
  try {
    const std::string payload = archive::unseal(kTrailsMagic, kTrailsVersion, checkpoint);
    archive::ByteReader r(payload);
    epoch = r.get<std::int64_t>();
    restored.generation = r.get<std::int64_t>();
    const auto n = r.get_count(2 * sizeof(double));
    if (n > options_.max_points)
      return "a trail of " + std::to_string(n) + " points (at most " + std::to_string(options_.max_points) + ")";
    std::shared_ptr<const Node> head;
    for (std::uint64_t i = 0; i < n; ++i) {
      const double x = r.get<double>();
      const double y = r.get<double>();
      if (!std::isfinite(x) || !std::isfinite(y)) return "a trail point is not finite";
      head = std::make_shared<const Node>(mapping::Point(x, y), std::move(head));
    }
    r.expect_end();
    restored.heads.push_back(std::move(head));
  } catch (const archive::ArchiveError& e) {
    return e.what();
  }
  restored.best = 0;
  restored.stand_in = true;
  generations_.clear();
  generations_.push_back(std::move(restored));
  epoch_ = epoch;
  return {};
}

mapping::MultiPolygon trail_corridor(const std::vector<mapping::Point>& trail, double half_width_m) {
  return dilated_polyline(trail, half_width_m);  // empty for an empty trail or a half-width <= 0
}

}  // namespace pex::planning
