#pragma once
// One polygonal map per SLAM particle (paper, section 4.1): every filter update
// the new generation's maps are their parents' maps — copied by sharing their
// immutable tiles — and the update's scan is inserted into each under that
// particle's pose. The best particle's map is then consistent with the best
// particle's whole trajectory at once, so a switch of the best particle (a loop
// closure) needs no refinement pass.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"

namespace pex::particle_maps {

struct ParticleMapsOptions {
  mapping::PolygonMapOptions map;
  int max_particles = 1000;  // an update with more is refused as bad input
  // Inserts of one update run on this many threads; each map is written by one
  // thread only, so the result does not depend on the count.
  int threads = 1;
};

// One particle of a filter update: its pose (map frame) when the scan was
// taken, and its parent's index in the previous update (-1 on the first).
struct ParticleState {
  geometry::Pose2 pose;
  int parent = -1;
};

// A scan in the sensor frame, and where the sensor sits on the robot.
struct SensorScan {
  std::span<const float> ranges;
  double angle_min = 0.0;        // rad
  double angle_increment = 0.0;  // rad
  geometry::Pose2 sensor_in_base; // m, m, rad
  // Per beam, 1 where the laser is blind (mapping::BlindBeams::mask; empty:
  // none): such a beam gives no free space in any particle's map.
  std::span<const std::uint8_t> blind;
};

struct UpdateResult {
  bool ok = false;             // false: nothing changed (bad input), see error
  std::string error;
  bool scan_inserted = false;  // false: the scan gave no polygon (maps copied only)
  int inserts = 0;             // distinct inserts done (equal children share one)
  int insert_failures = 0;     // inserts where some tile kept its old state
  // Per particle (as `particles`): beams without a return stopped at a wall
  // of the particle's map (ScanPolygonOptions::no_return_stops_at_walls).
  std::vector<int> no_return_beams_stopped;
};

// The scan polygon moved by a rigid transform (rotation about the origin by
// pose.theta, then translation). Validity is preserved up to rounding; the map
// validates every tile it writes anyway.
mapping::TypedPolygon transformed(const mapping::TypedPolygon& polygon, const geometry::Pose2& pose);
mapping::PreparedScan transformed(const mapping::PreparedScan& scan, const geometry::Pose2& pose);

class ParticleMaps {
 public:
  explicit ParticleMaps(ParticleMapsOptions options = {});

  // Applies one filter update. Parents must index the previous update's
  // particles (all -1, or valid indices, on the first update any parent is
  // ignored). On bad input (parent out of range, non-finite pose, too many
  // particles) nothing changes and ok is false.
  UpdateResult update(const std::vector<ParticleState>& particles, const SensorScan& scan,
                      const mapping::ScanPolygonOptions& scan_options);

  // Every one of `count` particles starts from `map` (its tiles shared). After a
  // break in the filter's lineage (updates missed, a restored checkpoint) the
  // best map known stands in for every particle's; the next update's parents
  // index these. count 0: no maps (the next update is a first one).
  void reseed(const mapping::PolygonMap& map, std::size_t count);

  std::size_t size() const { return maps_.size(); }
  const mapping::PolygonMap& map(std::size_t particle) const { return maps_.at(particle); }
  std::int64_t updates() const { return updates_; }

  // Heap bytes of all maps, each shared tile counted once.
  std::size_t memory_bytes() const;
  // Tiles over all maps, each shared tile counted once.
  std::size_t unique_tiles() const;

 private:
  ParticleMapsOptions options_;
  std::vector<mapping::PolygonMap> maps_;
  std::int64_t updates_ = 0;
};

}  // namespace pex::particle_maps
