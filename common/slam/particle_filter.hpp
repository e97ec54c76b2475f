#pragma once
// A Rao-Blackwellized particle filter for 2D SLAM as GMapping does it (Grisetti,
// Stachniss, Burgard, "Improved techniques for grid mapping with Rao-Blackwellized
// particle filters", IEEE T-RO 2007): every particle carries a pose, a map and
// its trajectory; each filter update samples the motion model, scan-matches the
// pose against the particle's map, draws the pose from the improved proposal,
// weighs the particle by the scan likelihood, resamples when the effective sample
// size falls below a threshold, and integrates the scan into every map.
//
// No clock and no I/O: scans and odometry come in, time is the scans' utime,
// and the random generator is seeded from the options.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "slam/cow_grid_map.hpp"
#include "slam/motion_model.hpp"
#include "slam/odometry_drift.hpp"
#include "slam/particle_map.hpp"
#include "slam/scan.hpp"
#include "slam/scan_constraint.hpp"
#include "slam/scan_matcher.hpp"

namespace pex::slam {

// Odometry that integrates the wheels' speed without its sign (FR079's: it
// reports driving backwards as driving forwards, with the correct signed
// velocity beside it, docs/slam.md) or whose wheels slip puts the prediction
// of an update up to twice the step off, far beyond the hill climb's reach, and
// the particles then all match into the wrong place at once. So each update
// first matches the best particle from the odometry step's translation scaled
// by each of `translation_scales` (heading change kept) and takes the scale
// whose match scores best, by more than `margin` over the measured step; every
// particle is then predicted from that step. One match per scale for one
// particle: a few percent of an update's cost.
struct OdometryCheckOptions {
  bool enabled = true;
  std::vector<double> translation_scales = {0.0, -1.0};  // tried beside the measured 1.0
  double min_translation_m = 0.1;  // shorter steps are not checked (too little to tell apart)
  double margin = 0.6;             // another scale must score this fraction better than the measured step (docs/slam.md)
};

struct ParticleFilterOptions {
  int particle_count = 30;
  // A filter update happens once the odometry has travelled this far (path
  // length) or turned this much since the last update.
  double linear_update_m = 0.5;
  double angular_update_rad = 0.25;
  // A robot that stops short of both gates (at a goal, on a pause) would
  // never have the view where it stands matched and mapped: the particles'
  // maps, and the polygon maps made at the updates, lack it until the robot
  // drives on (GMapping's temporalUpdate serves the same end). Once the
  // odometry has stayed within standing_tolerance_m / _rad of one pose for
  // standing_update_s of scan time, and that pose is more than
  // standing_update_min_m / _rad (net, not path: a standing base's encoder
  // jitter does not add up) from the pose of the last update, one update
  // runs there. 0: never.
  double standing_update_s = 0.5;
  double standing_tolerance_m = 0.005;
  double standing_tolerance_rad = 0.005;
  double standing_update_min_m = 0.01;
  double standing_update_min_rad = 0.01;
  // Resample when N_eff < resample_threshold * particle_count.
  double resample_threshold = 0.5;
  // Weights are exp(log_w / (likelihood_gain * particle_count)) before
  // normalising (GMapping's `ogain`): the per-beam likelihood treats beams as
  // independent, which overstates the evidence; the gain softens it.
  double likelihood_gain = 3.0;
  std::uint64_t seed = 1;
  // Threads that match particles in parallel. Results do not depend on it:
  // each particle's proposal draws come from its own generator, seeded from
  // (seed, generation, particle index).
  int threads = 1;
  MotionModelOptions motion;
  MatcherOptions matcher;
  ProposalOptions proposal;
  ScanConversionOptions scan;
  CowGridMapOptions grid;
  OdometryCheckOptions odometry_check;
  // Where the scan does not constrain the position (a corridor's length), a
  // particle's match is replaced by its motion-model sample (scan_constraint.hpp).
  ScanConstraintOptions constraint;
  // The odometry's systematic heading error, learnt from the matches and,
  // with odometry_drift.correct, taken out of every update's step
  // (odometry_drift.hpp).
  OdometryDriftOptions odometry_drift;
};

// Low-variance (systematic) resampling: parent index of each of the
// weights.size() children, with pointers spaced 1/n apart starting at
// first_pointer in [0, 1/n). Weights must be normalised.
std::vector<int> systematic_resample(const std::vector<double>& weights, double first_pointer);

// Makes the empty map of a particle; the filter's seam to the map representation.
using ParticleMapFactory = std::function<std::unique_ptr<ParticleMap>()>;

// A particle's pose after each update it took part in; nodes are shared by the
// descendants of a particle (GMapping's trajectory tree).
struct TrajectoryNode {
  Pose2 pose;
  std::int64_t generation = 0;
  std::shared_ptr<const TrajectoryNode> parent;
  TrajectoryNode(const Pose2& p, std::int64_t g, std::shared_ptr<const TrajectoryNode> up)
      : pose(p), generation(g), parent(std::move(up)) {}
  // Frees a long unshared chain iteratively (no deep recursion).
  ~TrajectoryNode();
};

struct Particle {
  Pose2 pose;                     // current pose (updated by odometry between updates)
  double log_weight = 0.0;        // accumulated since the last resampling
  double lineage_log_likelihood = 0.0;  // summed over the whole lineage; picks the best
  int parent = -1;                // index in the previous generation, -1 at the first
  std::unique_ptr<ParticleMap> map;
  std::shared_ptr<const TrajectoryNode> trajectory;
  Pose2 pose_at_update;           // pose after the last update (for the motion prior)
};

struct UpdateStats {
  std::int64_t generation = 0;
  bool resampled = false;
  double effective_sample_size = 0.0;
  int matcher_evaluations = 0;
  int failed_matches = 0;
  double odometry_scale = 1.0;  // the translation scale the odometry check chose (1: as measured)
  double odometry_check_ratio = 0.0;  // best other scale's match score / the measured step's (0: not checked)
  std::size_t points_beyond_map_extent = 0;  // end points the particles' maps left out (CowGridMapOptions::max_extent_m)
  int unconstrained_directions = 0;  // 0, 1 (a corridor) or 2: where the match gave way to the odometry
};

class ParticleFilter {
 public:
  explicit ParticleFilter(const ParticleFilterOptions& options, ParticleMapFactory map_factory = {});

  // Feeds a scan with the odometry pose at the scan's time. Moves every particle
  // by the odometry since the previous call and, if the robot moved enough since
  // the last update (or this is the first scan), runs a filter update. Returns
  // true when an update ran. A scan with no usable beam never triggers an update.
  bool process(const RangeScan& scan, const Pose2& odometry);

  bool initialized() const { return initialized_; }
  const std::vector<Particle>& particles() const { return particles_; }
  std::size_t best_index() const;
  // Normalised weights (after the likelihood gain), in particle order.
  std::vector<double> normalized_weights() const;
  // Generation of the last update (0 for the first), -1 before any.
  std::int64_t generation() const { return generation_; }
  const UpdateStats& last_update() const { return last_update_; }
  // Odometry pose at the last update: the best particle's pose plus the odometry
  // since then is the current best estimate.
  const Pose2& odometry_at_update() const { return odometry_at_update_; }
  // The current best estimate for a robot whose odometry reads `odometry`.
  Pose2 best_pose(const Pose2& odometry) const;
  // How far the best particle's lineage turned between the last two updates
  // (nullopt before two updates): the matcher's view of the robot's turn, which
  // the odometry pairing uses to estimate its clock offset (OdometryLagEstimator).
  std::optional<double> best_turn_at_last_update() const;
  // The odometry's travel (path length) and turn (summed |dtheta|) since the
  // last update: what the update gate measures.
  double travel_since_update_m() const { return linear_since_update_m_; }
  double turn_since_update_rad() const { return angular_since_update_rad_; }
  // Updates run because the robot stood (standing_update_s), of all updates.
  std::int64_t standing_updates() const { return standing_updates_; }
  // The best particle's pose at every update generation so far (index = generation).
  std::vector<Pose2> best_trajectory() const;

  // The filter survives a restart (issue 11). Its whole state as a sealed
  // archive (archive/byte_archive.hpp): every particle (pose, pose at the
  // update, weights, parent), the maps with each tile they share written once,
  // the trajectory tree with each shared node once (the whole tree, not only
  // the best path: any particle may be the best one later, and
  // best_trajectory() must then still reach back to generation 0), the
  // generator, the generation, the odometry bookkeeping. A restored filter fed
  // the same scans gives bit for bit what the one that never stopped gives.
  // Pure: bytes, no file. Throws std::logic_error for a filter made with a
  // custom map factory (only CowGridMap maps are written).
  std::string checkpoint() const;
  // Takes up a checkpoint: "" or why it was refused (cut short, damaged, of
  // another kind or format version, another particle count or grid
  // resolution); the filter is unchanged then. The options are this filter's
  // (the configuration's), not the saved ones.
  std::string restore(std::string_view checkpoint);

 private:
  void initialize(const ScanPoints& points, const Pose2& odometry, std::int64_t utime);
  // Follows where the odometry stands still (standing_update_s).
  void track_standing(std::int64_t utime, const Pose2& odometry);
  bool standing_update_due(std::int64_t utime, const Pose2& odometry) const;
  void update(const ScanPoints& points, const Pose2& odometry);
  void resample(const std::vector<double>& weights);
  // The odometry check (OdometryCheckOptions): the translation scale of this
  // update's odometry step, 1.0 when the measured step matches best. When it
  // ran, `measured_match` is the best particle's match from its own pose.
  double check_odometry_step(const ScanPoints& match_points, const Pose2& odometry_step, UpdateStats& stats,
                             std::optional<MatchResult>& measured_match) const;

  ParticleFilterOptions options_;
  ParticleMapFactory map_factory_;
  bool grid_maps_ = true;  // the maps are CowGridMaps (no custom factory): they can be checkpointed
  std::mt19937_64 rng_;
  std::vector<Particle> particles_;
  bool initialized_ = false;
  std::int64_t generation_ = -1;
  Pose2 last_odometry_;
  Pose2 odometry_at_update_;
  double linear_since_update_m_ = 0.0;
  double angular_since_update_rad_ = 0.0;
  // The odometry pose the robot has stayed near, and the scan time it came
  // there (standing_update_s).
  Pose2 standing_odometry_;
  std::int64_t standing_since_utime_ = 0;
  std::int64_t standing_updates_ = 0;
  UpdateStats last_update_;
  std::int64_t corrected_odometry_steps_ = 0;
  OdometryDrift drift_;
  std::int64_t points_beyond_map_extent_ = 0;
  std::int64_t unconstrained_updates_ = 0;

 public:
  // End points left out of the particles' maps, summed over the particles,
  // since this filter started (not checkpointed): nonzero means the robot is
  // at the edge of the extent the maps may cover.
  std::int64_t points_beyond_map_extent() const { return points_beyond_map_extent_; }
  // Updates whose scan left a direction unconstrained (ScanConstraintOptions),
  // since this filter started (not checkpointed).
  std::int64_t unconstrained_updates() const { return unconstrained_updates_; }
  // Updates whose odometry step the check replaced (OdometryCheckOptions).
  std::int64_t corrected_odometry_steps() const { return corrected_odometry_steps_; }
  // The odometry's drift as learnt so far (checkpointed).
  const OdometryDrift& odometry_drift() const { return drift_; }
};

}  // namespace pex::slam
