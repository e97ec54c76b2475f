#pragma once
// The polygon_mapper's adapter between LCM messages and pex::mapping: pairs
// each scan with the pose at its time, decides when a scan is inserted, and
// turns the merged planning map into a pex::polygon_map_t.
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>

#include <pex/laser_scan_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/slam_update_t.hpp>

#include "mapping/blind_beams.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"
#include "particle_maps/particle_maps.hpp"

namespace pex::runtime {
class ConfigReader;
}

namespace pex::polygon_mapper {

struct MapperOptions {
  // "odometry" (ODOMETRY), "sim_truth" (SIM_TRUTH): one map, scans inserted at
  // those poses. "slam" (SLAM_UPDATE): one map per particle, every update's scan
  // inserted under every particle's pose; the best particle's map is published.
  std::string pose_source = "odometry";
  double insert_min_distance_m = 0.2;     // insert a scan when the robot moved this far ...
  double insert_min_rotation_rad = 0.25;  // ... or turned this much since the last insert
  // ... or this long (scan time) after the last insert: a robot that stopped to
  // look at a frontier gets that look into the map (0 = never by time).
  double insert_max_interval_s = 1.0;
  double publish_rate_hz = 1.0;
  bool publish_free_space = true;         // MAP_FREE beside MAP, at the same rate
  double input_timeout_s = 3.0;           // no scan or no pose (with SLAM: SLAM_POSE) this long: DEGRADED (health)
  // Some beams blind this long (scan time) with no scan between that had
  // none: DEGRADED, saying where (blind_laser_reason). Glass and dark
  // surfaces at a slant blind a beam or a few for a moment (the Intel log:
  // 50 times 1-6 beams); a covered window stays.
  double blind_degraded_after_s = 5.0;
  double pose_buffer_s = 5.0;             // poses kept for pairing with scans
  double max_pose_gap_s = 0.5;            // poses bracketing a scan may be this far apart
  int max_pending_scans = 20;             // scans waiting for a newer pose
  mapping::ScanPolygonOptions scan;       // range_max_m caps the sensor's own range_max
  // Beams blind (no echo at the map's walls, scan after scan) give no free
  // space ([scan] blind_after_stopped_scans; mapping/blind_beams.hpp).
  mapping::BlindBeamOptions blind_beams;
  mapping::PolygonMapOptions map;
  int threads = 1;                        // slam: inserts of one update side by side
  // The published map (and the SLAM epoch it belongs to) across restarts,
  // written every checkpoint_period_s and on stop, read at start: "" = none.
  std::string checkpoint_file;
  double checkpoint_period_s = 2.0;
  // A saved map (pex-map save: GeoJSON) to start from when no checkpoint was
  // taken up, in the frame the poses will come in (the robot starts where that
  // map's frame has its origin): "" = none.
  std::string initial_map_file;
};

// Reads every key of config/polygon_mapper.toml; throws ConfigError on bad values.
MapperOptions load_options(runtime::ConfigReader& config);

struct TimedPose {
  std::int64_t utime = 0;
  geometry::Pose2 pose;
};

// Poses in time order; pose_at() interpolates (theta along the shorter arc).
class PoseBuffer {
 public:
  explicit PoseBuffer(double keep_s = 5.0) : keep_us_(static_cast<std::int64_t>(keep_s * 1e6)) {}
  // Poses older than the newest are dropped (out of order), as are non-finite ones.
  bool add(const TimedPose& pose);
  enum class Lookup { kOk, kTooOld, kTooNew, kGap, kEmpty };
  // The pose at `utime`, if two buffered poses at most max_gap_us apart bracket it.
  Lookup pose_at(std::int64_t utime, std::int64_t max_gap_us, geometry::Pose2& out) const;
  std::size_t size() const { return poses_.size(); }

 private:
  std::int64_t keep_us_;
  std::deque<TimedPose> poses_;
};

struct MapperCounters {
  std::int64_t scans_received = 0;
  std::int64_t scans_inserted = 0;
  std::int64_t scans_skipped_no_motion = 0;
  std::int64_t scans_without_pose = 0;
  std::int64_t scan_polygon_errors = 0;
  std::int64_t failed_tile_updates = 0;
  std::int64_t merge_failures = 0;
  // Tiles of the last published map whose planning layer could not be
  // derived (they show their last good planning layer).
  std::int64_t stale_planning_tiles = 0;
  std::int64_t slam_updates = 0;          // slam: updates applied
  std::int64_t updates_without_scan = 0;  // slam: updates whose scan never arrived
  std::int64_t best_switches = 0;         // slam: the best particle changed
  // slam: updates that did not continue the maps held (an update missed, a
  // SLAM restored from an older checkpoint, this mapper restored): every
  // particle went on from the best map held.
  std::int64_t slam_resyncs = 0;
  // slam: a SLAM started afresh (another epoch, another map frame): the maps
  // of the old one were dropped, never mixed with the new.
  std::int64_t slam_epoch_changes = 0;
  // Beams without a return that ran into a wall the map holds and were
  // stopped there (ScanPolygonOptions::no_return_stops_at_walls; the best
  // particle's, on SLAM). A steady climb while the robot drives is a laser
  // blind in some sector; a few a scan are glass or dark surfaces.
  std::int64_t no_return_beams_stopped = 0;

  // By name, for DAEMON_STATUS (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    v.total("scans_inserted", scans_inserted);
    v.total("scans_skipped_no_motion", scans_skipped_no_motion);
    v.total("scans_without_pose", scans_without_pose);
    v.total("scan_polygon_errors", scan_polygon_errors);
    v.total("failed_tile_updates", failed_tile_updates);
    v.total("merge_failures", merge_failures);
    v.total("stale_planning_tiles", stale_planning_tiles);
    v.total("slam_updates", slam_updates);
    v.total("updates_without_scan", updates_without_scan);
    v.total("best_switches", best_switches);
    v.total("slam_resyncs", slam_resyncs);
    v.total("slam_epoch_changes", slam_epoch_changes);
    v.total("no_return_beams_stopped", no_return_beams_stopped);
  }
};

class Mapper {
 public:
  explicit Mapper(MapperOptions options);

  // Throws std::invalid_argument for a malformed scan (bad angles, sizes).
  void on_scan(const pex::laser_scan_t& scan);
  // A pose from the configured source.
  void on_pose(const TimedPose& pose);
  // pose_source "slam": one filter update. Returns true when the best particle
  // changed, so the caller publishes the new best map at once. Throws
  // std::invalid_argument for a malformed update (sizes, best index, parents).
  bool on_slam_update(const pex::slam_update_t& update);

  // The MAP message of the current map (merged only when the map changed). If
  // the merge fails the last good message is kept (counted), so a published
  // map is always valid. nullopt until a scan was inserted.
  std::optional<pex::polygon_map_t> map_message(std::int64_t now_utime);
  // The MAP_FREE message: the explored free space, the union of the scan
  // polygons with their obstacle / frontier edges (the paper's map), without
  // the obstacle band MAP subtracts for planning. What the robot has seen is
  // scored on it: on a thin wall the band takes obstacle_outer_m of the floor
  // on the wall's far side, floor the robot has seen. Same caching and
  // failure rule as map_message().
  std::optional<pex::polygon_map_t> free_space_message(std::int64_t now_utime);

  const MapperCounters& counters() const { return counters_; }
  // Where the laser is blind, or the map off the world: the blind beams'
  // count and their bearings in the sensor frame, for the daemon's DEGRADED
  // reason; "" when every beam sees, or some have been blind for less than
  // blind_degraded_after_s of scan time. The map is still built, but the
  // laser sees less of it.
  std::string blind_laser_reason() const;
  // The counters and the map's size, for DAEMON_STATUS (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    counters_.visit_counters(v);
    v.total("map_vertices", static_cast<std::int64_t>(map().planning_vertex_count()));
    // The laser's blind beams now (no echo at a wall the map holds, scan
    // after scan), how often it went from none blind to some, and the beams
    // without an echo since the start: none of them gives free space.
    v.total("blind_beams", blind_.count());
    v.total("blind_onsets", blind_.onsets());
    v.total("never_echoed_beams", blind_.never_echoed());
  }
  // Which beams of the laser are blind (mapping/blind_beams.hpp), from the scans inserted.
  const mapping::BlindBeams& blind_beams() const { return blind_; }
  // The map that is published: the single map, or the best particle's.
  const mapping::PolygonMap& map() const;
  // slam: the per-particle maps (empty before the first update).
  const particle_maps::ParticleMaps& particle_maps() const { return particle_maps_; }
  const MapperOptions& options() const { return options_; }

  // The map survives a restart: the published map (the best particle's) with
  // the SLAM lineage it belongs to, as a sealed archive (archive/byte_archive.hpp).
  std::string checkpoint() const;
  // Takes up a checkpoint before the first input: "" or why it was refused
  // (damaged, another pose source, another tile grid); then nothing changed.
  // With pose_source "slam" the restored map stands in for every particle
  // once an update of the same epoch arrives, and is dropped if SLAM's epoch
  // is another (its frame is not the map's).
  std::string restore(std::string_view checkpoint);
  // Starts from a saved map (initial_map_file) before the first input: its
  // polygons inserted as one scan each; with pose_source "slam" the map stands
  // in for every particle at the first update, whatever SLAM's epoch (a saved
  // map has none). "" or why refused (a map is already held); then nothing changed.
  std::string start_from(const mapping::TypedMultiPolygon& polygons);

 private:
  void process_pending();
  // Inserts if the robot moved enough; false if the scan must wait for a pose.
  bool try_insert(const pex::laser_scan_t& scan);
  // slam: applies waiting updates in order while their scans are here.
  void drain_waiting_updates();
  // slam: applies the update if its scan is here; false if the scan is not.
  bool apply_slam_update(const pex::slam_update_t& update);
  // The bearings of the beams and the time of `scan`, after blind_ observed it.
  void note_blind_scan(const pex::laser_scan_t& scan);
  // The scan-polygon options with the sensor's own range limits applied.
  mapping::ScanPolygonOptions scan_options_for(const pex::laser_scan_t& scan) const;
  // The map changed: both messages are merged anew when next asked for.
  void mark_changed() { dirty_ = free_space_dirty_ = true; }
  // A merge into its cached message: encoded if it succeeded (the message is
  // then clean), else counted and the last good message kept.
  void take_merge(const mapping::MergeResult& merged, std::optional<pex::polygon_map_t>& message, bool& dirty);
  // The cached message with this moment's stamps, or nullopt if none yet.
  std::optional<pex::polygon_map_t> stamped(std::optional<pex::polygon_map_t>& message, std::int64_t now_utime) const;

  MapperOptions options_;
  PoseBuffer poses_;
  std::deque<pex::laser_scan_t> pending_;
  mapping::PolygonMap map_;
  std::optional<geometry::Pose2> last_insert_pose_;
  std::int64_t last_insert_scan_utime_ = -1;
  std::int64_t last_scan_utime_ = 0;
  std::optional<pex::polygon_map_t> message_;
  bool dirty_ = false;
  std::optional<pex::polygon_map_t> free_space_message_;
  bool free_space_dirty_ = false;
  MapperCounters counters_;
  // slam
  particle_maps::ParticleMaps particle_maps_;
  std::deque<pex::slam_update_t> waiting_updates_;  // their scan has not arrived yet
  mapping::BlindBeams blind_;  // the laser's, from the scans inserted (both pose sources)
  double blind_angle_min_rad_ = 0.0;        // bearing of blind_'s beam 0 ...
  double blind_angle_increment_rad_ = 0.0;  // ... and between its beams (the scan it last observed)
  std::int64_t blind_since_utime_ = -1;     // scan time since which some beam is blind (-1: none is)
  std::int64_t blind_seen_utime_ = -1;      // the scan time blind_ last observed
  int best_ = -1;
  std::int64_t epoch_ = 0;       // SLAM lineage of the maps held (slam_update_t.epoch)
  std::int64_t generation_ = 0;  // of the last update applied
  // A restored map waiting for the first update (slam): published meanwhile.
  std::optional<mapping::PolygonMap> restored_;
  bool restored_any_epoch_ = false;  // restored_ is a saved map: taken up by any epoch
};

// The MAP message for a typed multipolygon (outer rings CCW, holes CW).
pex::polygon_map_t to_message(const mapping::TypedMultiPolygon& polygons);

}  // namespace pex::polygon_mapper
