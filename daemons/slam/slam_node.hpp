#pragma once
// The slam daemon's handlers, shared by the live daemon and `pex-slam --log`:
// LIDAR_SCAN and ODOMETRY in, SLAM_UPDATE and SLAM_POSE out (through `publish`
// callbacks, so this class knows no transport), and the trajectory of every
// scan for the offline pose file.
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include <pex/laser_scan_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/slam_update_t.hpp>

#include "slam/odometry_sync.hpp"
#include "slam/particle_filter.hpp"
#include "slam/trajectory_recorder.hpp"

namespace pex::slam_daemon {

struct SlamNodeOptions {
  slam::ParticleFilterOptions filter;
  slam::OdometrySyncOptions sync;
  std::size_t max_beams = 8192;  // a scan with more is refused as bad input
  // A scan whose laser is mounted farther than this from the robot's centre
  // is refused: its hits land that far away, and the grid grew to hold them
  // (2.3e6 m asked for 500 TB; found by the fuzz target slam_input).
  double max_sensor_offset_m = 10.0;
  // With no filter update for this long (scan time), the particle set is
  // published again with the current scan: identity parents, no resampling,
  // the filter untouched. A standing robot makes no updates (but the one of
  // ParticleFilterOptions::standing_update_s where it stopped), and a mapper
  // (re)started meanwhile would wait for one for ever while the explorer
  // waits for its map. 0 = never.
  double republish_period_s = 1.0;
  // ... but only while the robot stands: odometry travel and turn since the
  // last update at most these. Between updates a particle's pose is odometry
  // plus sampled motion noise, unmatched: a robot driving at 0.4 m/s took
  // longer than the period for the 0.5 m gate, and the scans republished
  // at those poses were 2-4 degrees off (0.4 m at 7 m) and drew slanted walls
  // across rooms and doors in the polygon maps (office, 2026-11-25).
  double republish_max_travel_m = 0.01;
  double republish_max_turn_rad = 0.01;
  double input_timeout_s = 3.0;  // no LIDAR_SCAN or no ODOMETRY this long: DEGRADED (health)
  // The filter across restarts (SlamNode::checkpoint), written every
  // checkpoint_period_s (node clock) and on stop, read at start: "" = none.
  std::string checkpoint_file;
  double checkpoint_period_s = 2.0;
  // Keep every scan's time and odometry (64 B a scan) for trajectory_text():
  // the offline pose file (`pex-slam --log --poses`). Live it is off: it grows
  // with the run's length (18 MB for 8 hours of a 10 Hz laser) for nothing.
  bool record_trajectory = false;
  // trajectory_text(): the next update's correction spread over the scans
  // before it (TrajectoryRecorder::resolve), or (false) every scan's pose its
  // update's carried forward by odometry, as the robot knew it at the scan.
  bool spread_corrections = true;
};

struct SlamOutputs {
  std::function<void(const slam_update_t&)> publish_update;
  std::function<void(const pose_t&)> publish_pose;
};

class SlamNode {
 public:
  SlamNode(const SlamNodeOptions& options, SlamOutputs outputs);

  // Throw std::invalid_argument for content they refuse (non-finite pose,
  // array sizes that disagree, too many beams); the state is unchanged then.
  void on_odometry(const odometry_t& msg);
  const slam::OdometrySync& odometry_sync() const { return sync_; }
  void on_scan(const laser_scan_t& msg);
  // Processes scans still waiting for odometry (end of a log).
  void flush();

  // `timestamp_s x y theta` for every scan processed so far (with
  // record_trajectory; none without), on the best particle's trajectory, the
  // next update's correction spread over the scans between updates
  // (TrajectoryRecorder::resolve).
  std::string trajectory_text() const;

  const slam::ParticleFilter& filter() const { return filter_; }
  std::int64_t scans_processed() const { return scans_processed_; }
  std::int64_t republished() const { return republished_; }
  // By name, for DAEMON_STATUS (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    v.total("scans_processed", scans_processed_);
    v.total("filter_updates", filter_.generation() + 1);
    v.total("updates_republished", republished_);
    v.total("standing_updates", filter_.standing_updates());
    v.total("corrected_odometry_steps", filter_.corrected_odometry_steps());
    v.total("unconstrained_updates", filter_.unconstrained_updates());
    // The learnt drift in micro-units (counters are integers): urad per
    // metre driven and ppm of every turn.
    v.total("odometry_drift_urad_per_m", std::llround(filter_.odometry_drift().drift_rad_per_m() * 1e6));
    v.total("odometry_turn_scale_ppm", std::llround(filter_.odometry_drift().turn_scale() * 1e6));
    v.total("odometry_drift_steps", filter_.odometry_drift().observations());
    v.total("scans_without_odometry", static_cast<std::int64_t>(sync_.stale_pairings()));
    v.total("odometry_resets", static_cast<std::int64_t>(sync_.odometry_resets()));
    v.event("odometry_impossible_steps", static_cast<std::int64_t>(sync_.impossible_steps()));
    v.event("points_beyond_map_extent", filter_.points_beyond_map_extent());
  }
  // The filter's lineage (slam_update_t.epoch): 0 before the first update.
  std::int64_t epoch() const { return epoch_; }

  // SLAM survives a restart (issue 11): the filter (ParticleFilter::checkpoint),
  // the odometry pairing (its frame: a restored SLAM does not jump) and what
  // makes the restored node's next update the continuation of the saved one's
  // for the mapper: the same epoch, the filter's generation, the scan time of
  // the last publication (the republish timer), the counters. A sealed archive.
  // Not in it: the per-scan trajectory of the offline pose file
  // (trajectory_text), which one `pex-slam --log` run makes from the log's
  // start; after a restore it covers the scans since.
  std::string checkpoint() const;
  // Takes up a checkpoint: "" or why it was refused (damaged, another version,
  // another particle count or grid); then nothing changed.
  std::string restore(std::string_view checkpoint);

 private:
  void process(std::vector<slam::PairedScan> ready);
  slam_update_t update_message(std::int64_t scan_utime) const;
  // The particle set now, as an update that changes no lineage (republish).
  slam_update_t republish_message(std::int64_t scan_utime) const;

  SlamNodeOptions options_;
  SlamOutputs outputs_;
  slam::ParticleFilter filter_;
  slam::OdometrySync sync_;
  slam::TrajectoryRecorder recorder_;
  std::int64_t scans_processed_ = 0;
  std::int64_t last_published_scan_utime_ = -1;
  std::int64_t republished_ = 0;
  std::int64_t epoch_ = 0;
};

}  // namespace pex::slam_daemon
