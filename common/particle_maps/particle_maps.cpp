#include "particle_maps/particle_maps.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <set>
#include <thread>
#include <tuple>

#include "geometry/point.hpp"
#include "mapping/blind_beams.hpp"
#include "mapping/known_walls.hpp"

namespace pex::particle_maps {

using geometry::Pose2;

namespace {
void move_polygon(mapping::Polygon& polygon, const Pose2& pose) {
  const geometry::PoseTransform to_map(pose);
  auto move = [&](mapping::Ring& ring) {
    for (auto& p : ring) p = to_map(p);
  };
  move(polygon.outer());
  for (auto& inner : polygon.inners()) move(inner);
}
}  // namespace

mapping::TypedPolygon transformed(const mapping::TypedPolygon& polygon, const Pose2& pose) {
  mapping::TypedPolygon out = polygon;
  move_polygon(out.geometry, pose);
  return out;
}

mapping::PreparedScan transformed(const mapping::PreparedScan& scan, const Pose2& pose) {
  mapping::PreparedScan out = scan;
  move_polygon(out.polygon.geometry, pose);
  for (auto& polygon : out.band) move_polygon(polygon, pose);
  return out;
}

ParticleMaps::ParticleMaps(ParticleMapsOptions options) : options_(std::move(options)) {}

void ParticleMaps::reseed(const mapping::PolygonMap& map, std::size_t count) { maps_.assign(count, map); }

UpdateResult ParticleMaps::update(const std::vector<ParticleState>& particles, const SensorScan& scan,
                                  const mapping::ScanPolygonOptions& scan_options) {
  UpdateResult r;
  if (particles.empty() || static_cast<int>(particles.size()) > options_.max_particles) {
    r.error = "particle count " + std::to_string(particles.size()) + " not in [1, " +
              std::to_string(options_.max_particles) + "]";
    return r;
  }
  const bool first = maps_.empty();
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const auto& p = particles[i];
    if (!geometry::is_finite(p.pose)) {
      r.error = "particle " + std::to_string(i) + " has a non-finite pose";
      return r;
    }
    if (!first && (p.parent < 0 || p.parent >= static_cast<int>(maps_.size()))) {
      r.error = "particle " + std::to_string(i) + " names parent " + std::to_string(p.parent) +
                " of a generation of " + std::to_string(maps_.size());
      return r;
    }
  }

  // The scan's polygon and obstacle band once, in the sensor frame; each
  // particle gets a moved copy.
  // Blind beams give no free space (their extents at the minimum range),
  // in the shared polygon and in each particle's own.
  auto with_blind = [&](std::span<const float> stopped_extent_m) {
    return mapping::without_blind_beams(scan.ranges, scan_options.range_min_m, scan_options.range_max_m,
                                        stopped_extent_m, scan_options.free_range_m, scan.blind);
  };
  const mapping::ScanPolygonResult local = mapping::scan_to_polygon(
      scan.ranges, scan.angle_min, scan.angle_increment, Pose2{}, scan_options, with_blind({}));
  const mapping::PreparedScan prepared =
      local.ok ? mapping::prepare_scan(local.polygon, options_.map) : mapping::PreparedScan{};

  std::vector<mapping::PolygonMap> next;
  next.reserve(particles.size());
  // Children of one parent at bit-identical poses get identical maps: insert once.
  std::map<std::tuple<int, double, double, double>, std::size_t> first_with_key;
  std::vector<std::size_t> copy_of(particles.size());  // index whose map this one repeats
  std::vector<std::size_t> to_insert;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const auto& p = particles[i];
    const int parent = first ? -1 : p.parent;
    const auto [it, inserted] = first_with_key.emplace(std::make_tuple(parent, p.pose.x_m, p.pose.y_m, p.pose.theta_rad), i);
    copy_of[i] = it->second;
    next.push_back(first ? mapping::PolygonMap(options_.map) : maps_[static_cast<std::size_t>(parent)]);
    if (inserted && local.ok) to_insert.push_back(i);
  }
  // The inserts: each touches its own map only, so they can run side by side.
  std::vector<char> failed(particles.size(), 0);
  std::vector<int> stopped(particles.size(), 0);
  // A beam without a return ends at a wall of the particle's own map (its
  // parent's, before this scan): each particle whose map stops one gets its
  // own polygon, built at its pose; the rest share the one above
  // (no_return_extents_in reads the option; a first scan has no map to stop it).
  const bool stop_at_walls = !first;
  // Inserts differ in cost (a particle's scan may touch more tiles), so each
  // worker takes the next one as it is free rather than a fixed share.
  std::atomic<std::size_t> next_insert{0};
  auto work = [&] {
    for (std::size_t k; (k = next_insert.fetch_add(1)) < to_insert.size();) {
      const std::size_t i = to_insert[k];
      const Pose2 sensor = geometry::compose(particles[i].pose, scan.sensor_in_base);
      if (stop_at_walls) {
        const auto extents = mapping::no_return_extents_in(next[i], scan.ranges, scan.angle_min,
                                                           scan.angle_increment, sensor, scan_options);
        stopped[i] = extents.beams_stopped;
        if (extents.beams_stopped > 0) {
          const auto own = mapping::scan_to_polygon(scan.ranges, scan.angle_min, scan.angle_increment, sensor,
                                                    scan_options, with_blind(extents.extent_m));
          if (own.ok) {
            const auto result = next[i].insert(mapping::prepare_scan(own.polygon, options_.map));
            failed[i] = result.ok ? 0 : 1;
            continue;
          }
        }
      }
      const auto result = next[i].insert(transformed(prepared, sensor));
      failed[i] = result.ok ? 0 : 1;
    }
  };
  const std::size_t workers =
      std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(options_.threads), to_insert.size()));
  std::vector<std::thread> pool;
  for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  for (std::size_t i = 0; i < particles.size(); ++i)
    if (copy_of[i] != i) {
      next[i] = next[copy_of[i]];
      stopped[i] = stopped[copy_of[i]];
    }
  r.no_return_beams_stopped = std::move(stopped);
  r.inserts = static_cast<int>(to_insert.size());
  for (char f : failed) r.insert_failures += f;
  maps_ = std::move(next);
  ++updates_;
  r.ok = true;
  r.scan_inserted = local.ok;
  if (!local.ok) r.error = "scan gave no polygon: " + local.error;
  return r;
}

std::size_t ParticleMaps::unique_tiles() const {
  std::set<const mapping::Tile*> seen;
  for (const auto& m : maps_)
    for (const auto& [key, tile] : m.tiles()) seen.insert(tile.get());
  return seen.size();
}

std::size_t ParticleMaps::memory_bytes() const {
  std::set<const mapping::Tile*> seen;
  std::size_t bytes = 0;
  for (const auto& m : maps_) {
    // The table of tile pointers is each map's own.
    bytes += sizeof(mapping::PolygonMap) +
             m.tiles().size() * (sizeof(mapping::PolygonMap::TileKey) + 2 * sizeof(void*) + 32);
    for (const auto& [key, tile] : m.tiles()) {
      if (!seen.insert(tile.get()).second) continue;
      bytes += tile->memory_bytes();
    }
  }
  return bytes;
}

}  // namespace pex::particle_maps
