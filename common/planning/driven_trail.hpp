#pragma once
// Where the robot has driven, as each SLAM particle has it, and the corridor
// that way leaves in the configuration space.
//
// Why: a gap a few centimetres wider than the robot (a chair by a passage's
// corner, a door with a cabinet beside it) is open in one map and shut in the
// next, as SLAM's corrections and the obstacle bands of new scans move its
// sides by a few centimetres. A robot that has driven through it is then shut
// in on the far side, with the frontiers it left behind "without a path"
// (generated office floor 7, session 32: coverage 0.80 when the gap closed
// behind it). The way the robot drove is the one certain proof of where its
// disk fits. Each particle's map is built from that particle's poses, so its
// trail is consistent with its map: the best particle's trail runs through
// the gap where its map has it, not where an older best particle had it.
// Pure: no clock, no I/O.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct DrivenTrailOptions {
  // A particle's trail gets a point when its pose is this far from the
  // trail's last point (a standing robot adds none).
  double min_spacing_m = 0.05;
  // Trails are kept for this many filter generations back: the map a plan
  // uses lags the newest filter update by the mapper's work.
  int kept_generations = 32;
  // A trail is given out with at most this many points (the newest).
  std::size_t max_points = 200'000;
  int max_particles = 1000;  // an update with more is refused as bad input
};

// One particle of a filter update: its pose (map frame) and its parent's
// index in the previous update (ignored on a first update).
struct TrailParticle {
  geometry::Pose2 pose;
  int parent = -1;
};

// What a filter update is, for the trails (as SLAM_UPDATE has it).
struct TrailUpdate {
  std::int64_t epoch = 0;       // the filter's lineage: another epoch is another frame
  std::int64_t generation = 0;  // counts filter updates
  bool republished = false;     // the same generation again (no filter update ran)
  int best = 0;
  std::vector<TrailParticle> particles;
};

// The particles' trails, copied with the particles on resampling (each
// child's trail is its parent's and its own new pose: the points are shared,
// not copied). Single-threaded.
class DrivenTrails {
 public:
  explicit DrivenTrails(DrivenTrailOptions options = {});
  ~DrivenTrails();
  DrivenTrails(const DrivenTrails&) = delete;
  DrivenTrails& operator=(const DrivenTrails&) = delete;
  DrivenTrails(DrivenTrails&&) noexcept;
  DrivenTrails& operator=(DrivenTrails&&) noexcept;

  struct Result {
    bool ok = false;
    std::string error;  // why refused (nothing changed)
    // The update did not follow the last one (a missed update, a restarted
    // SLAM with the same epoch): every particle took the best trail held.
    bool resynced = false;
    bool new_epoch = false;  // another frame: the trails started afresh
  };
  // Applies one update. Refused (nothing changes): no particles, more than
  // max_particles, a pose not finite, best or a parent out of range.
  Result update(const TrailUpdate& update);

  // Particle `particle`'s trail at `generation` of the current epoch, oldest
  // point first; nullopt when that generation is not kept or has no such particle.
  std::optional<std::vector<mapping::Point>> trail(std::int64_t generation, int particle) const;
  // The best particle's trail at the newest generation (empty when none).
  std::vector<mapping::Point> best_trail() const;
  std::optional<std::int64_t> newest_generation() const;

  // The trails across a restart of whoever keeps them (the explorer's
  // checkpoint): the best particle's newest trail (at most max_points, the
  // newest), its epoch and generation, as a sealed archive ("" when nothing is
  // held). Why only the best: it is the trail a resync hands every particle.
  std::string checkpoint() const;
  // Takes a checkpoint up: its trail stands in for every particle's at its
  // generation (what trail() gives for any particle there) until the next
  // update, which resyncs on it if it is of the same epoch (the particles'
  // parents index an update not seen here) and starts afresh if not. Returns
  // "" when taken up, else why not (nothing changed).
  std::string restore(std::string_view checkpoint);

  struct Node;  // driven_trail.cpp

 private:
  struct Generation {
    std::int64_t generation = 0;
    int best = 0;
    std::vector<std::shared_ptr<const Node>> heads;  // per particle; null: no point yet
    bool stand_in = false;  // restored: one trail for every particle (restore())
  };
  std::vector<mapping::Point> flatten(const std::shared_ptr<const Node>& head) const;

  DrivenTrailOptions options_;
  std::optional<std::int64_t> epoch_;
  std::vector<Generation> generations_;  // oldest first
};

// The corridor of half-width `half_width_m` about a trail: the positions of
// the robot's centre within that distance of where it has been. The C-space
// keeps it open where it joins pieces (ConfigurationSpace::build, given the
// trail as a DrivenWay, dilates only the stretches that matter there:
// way_near_or_outside). Empty for an empty trail or half-width <= 0.
mapping::MultiPolygon trail_corridor(const std::vector<mapping::Point>& trail, double half_width_m);

}  // namespace pex::planning
