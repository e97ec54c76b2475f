#include "mapper.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "archive/byte_archive.hpp"
#include "mapping/known_walls.hpp"
#include "mapping/map_archive.hpp"
#include "runtime/config.hpp"

namespace pex::polygon_mapper {

namespace {

bool finite(double v) { return std::isfinite(v); }

}  // namespace

MapperOptions load_options(runtime::ConfigReader& config) {
  using runtime::positive;
  using runtime::non_negative;
  MapperOptions o;
  o.pose_source = config.get<std::string>("pose_source", o.pose_source,
                                          runtime::one_of({"odometry", "sim_truth", "slam"}));
  o.threads = config.get<int>("threads", o.threads, runtime::in_range(1, 64));
  o.insert_min_distance_m = config.get<double>("insert_min_distance_m", o.insert_min_distance_m, non_negative<double>());
  o.insert_min_rotation_rad = config.get<double>("insert_min_rotation_rad", o.insert_min_rotation_rad, non_negative<double>());
  o.insert_max_interval_s = config.get<double>("insert_max_interval_s", o.insert_max_interval_s, non_negative<double>());
  o.publish_rate_hz = config.get<double>("publish_rate_hz", o.publish_rate_hz, runtime::in_range(0.01, 100.0));
  o.publish_free_space = config.get<bool>("publish_free_space", o.publish_free_space);
  o.input_timeout_s = config.get<double>("input_timeout_s", o.input_timeout_s, runtime::in_range(0.1, 3600.0));
  o.blind_degraded_after_s =
      config.get<double>("blind_degraded_after_s", o.blind_degraded_after_s, runtime::in_range(0.0, 3600.0));
  o.pose_buffer_s = config.get<double>("pose_buffer_s", o.pose_buffer_s, positive<double>());
  o.max_pose_gap_s = config.get<double>("max_pose_gap_s", o.max_pose_gap_s, positive<double>());
  o.max_pending_scans = config.get<int>("max_pending_scans", o.max_pending_scans, runtime::in_range(1, 1000));
  o.checkpoint_file = config.get_path("checkpoint_file", o.checkpoint_file, /*must_exist=*/false);
  o.checkpoint_period_s = config.get<double>("checkpoint_period_s", o.checkpoint_period_s, runtime::in_range(0.1, 3600.0));
  o.initial_map_file = config.get_path("initial_map_file", o.initial_map_file, /*must_exist=*/true);
  auto scan = config.section("scan");
  o.scan.range_min_m = scan.get<double>("range_min_m", o.scan.range_min_m, non_negative<double>());
  o.scan.range_max_m = scan.get<double>("range_max_m", o.scan.range_max_m, positive<double>());
  o.scan.free_range_m = scan.get<double>("free_range_m", o.scan.free_range_m, positive<double>());
  o.scan.obstacle_range_m =
      scan.get<double>("obstacle_range_m", o.scan.obstacle_range_m, runtime::in_range(0.0, 1000.0));
  o.scan.return_margin_m = scan.get<double>("return_margin_m", o.scan.return_margin_m, runtime::in_range(0.0, 0.5));
  o.scan.break_lambda_rad = scan.get<double>("break_lambda_rad", o.scan.break_lambda_rad, runtime::in_range(0.01, 1.5));
  o.scan.break_sigma_m = scan.get<double>("break_sigma_m", o.scan.break_sigma_m, non_negative<double>());
  o.scan.break_max_gap_m = scan.get<double>("break_max_gap_m", o.scan.break_max_gap_m, non_negative<double>());
  o.scan.rdp_epsilon_m = scan.get<double>("rdp_epsilon_m", o.scan.rdp_epsilon_m, non_negative<double>());
  o.scan.merge_max_rms_m = scan.get<double>("merge_max_rms_m", o.scan.merge_max_rms_m, non_negative<double>());
  o.scan.merge_max_deviation_m =
      scan.get<double>("merge_max_deviation_m", o.scan.merge_max_deviation_m, non_negative<double>());
  o.scan.least_squares_refit = scan.get<bool>("least_squares_refit", o.scan.least_squares_refit);
  o.scan.refit_max_shift_m = scan.get<double>("refit_max_shift_m", o.scan.refit_max_shift_m, non_negative<double>());
  o.scan.free_arc_step_rad = scan.get<double>("free_arc_step_rad", o.scan.free_arc_step_rad, runtime::in_range(0.001, 1.0));
  o.scan.max_beams = scan.get<int>("max_beams", o.scan.max_beams, runtime::in_range(2, 1000000));
  o.scan.min_returns = scan.get<int>("min_returns", o.scan.min_returns, runtime::in_range(0, 1000000));
  o.scan.no_return_stops_at_walls = scan.get<bool>("no_return_stops_at_walls", o.scan.no_return_stops_at_walls);
  o.blind_beams.after_stopped_scans =
      scan.get<int>("blind_after_stopped_scans", o.blind_beams.after_stopped_scans, runtime::in_range(0, 1000));
  o.blind_beams.no_free_space_before_first_echo =
      scan.get<bool>("no_free_space_before_first_echo", o.blind_beams.no_free_space_before_first_echo);
  auto map = config.section("map");
  o.map.tile_size_m = map.get<double>("tile_size_m", o.map.tile_size_m, runtime::in_range(1.0, 1000.0));
  o.map.tile_origin_m = map.get<double>("tile_origin_m", o.map.tile_origin_m, runtime::in_range(-1e5, 1e5));
  o.map.obstacle_inner_m = map.get<double>("obstacle_inner_m", o.map.obstacle_inner_m, non_negative<double>());
  o.map.obstacle_outer_m = map.get<double>("obstacle_outer_m", o.map.obstacle_outer_m, positive<double>());
  o.map.obstacle_end_trim_m =
      map.get<double>("obstacle_end_trim_m", o.map.obstacle_end_trim_m, runtime::in_range(0.0, 1.0));
  o.map.simplify_epsilon_m = map.get<double>("simplify_epsilon_m", o.map.simplify_epsilon_m, non_negative<double>());
  if (o.scan.free_range_m > o.scan.range_max_m)
    throw runtime::ConfigError(config.origin() + ": scan.free_range_m (" + std::to_string(o.scan.free_range_m) +
                               ") must not exceed scan.range_max_m (" + std::to_string(o.scan.range_max_m) + ")");
  return o;
}

bool PoseBuffer::add(const TimedPose& pose) {
  if (!finite(pose.pose.x_m) || !finite(pose.pose.y_m) || !finite(pose.pose.theta_rad)) return false;
  if (!poses_.empty() && pose.utime <= poses_.back().utime) return false;
  poses_.push_back(pose);
  while (!poses_.empty() && poses_.front().utime < pose.utime - keep_us_) poses_.pop_front();
  return true;
}

PoseBuffer::Lookup PoseBuffer::pose_at(std::int64_t utime, std::int64_t max_gap_us, geometry::Pose2& out) const {
  if (poses_.empty()) return Lookup::kEmpty;
  if (utime < poses_.front().utime) return Lookup::kTooOld;
  if (utime > poses_.back().utime) return Lookup::kTooNew;
  // First pose at or after utime.
  auto it = std::lower_bound(poses_.begin(), poses_.end(), utime,
                             [](const TimedPose& p, std::int64_t t) { return p.utime < t; });
  if (it->utime == utime) {
    out = it->pose;
    return Lookup::kOk;
  }
  const TimedPose& b = *it;
  const TimedPose& a = *(it - 1);
  if (b.utime - a.utime > max_gap_us) return Lookup::kGap;
  const double s = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
  out.x_m = a.pose.x_m + s * (b.pose.x_m - a.pose.x_m);
  out.y_m = a.pose.y_m + s * (b.pose.y_m - a.pose.y_m);
  out.theta_rad = geometry::wrap_angle(a.pose.theta_rad + s * geometry::wrap_angle(b.pose.theta_rad - a.pose.theta_rad));
  return Lookup::kOk;
}

Mapper::Mapper(MapperOptions options)
    : options_(std::move(options)),
      poses_(options_.pose_buffer_s),
      map_(options_.map),
      particle_maps_(particle_maps::ParticleMapsOptions{options_.map, 1000, options_.threads}),
      blind_(options_.blind_beams) {}

void Mapper::note_blind_scan(const pex::laser_scan_t& scan) {
  blind_angle_min_rad_ = scan.angle_min;
  blind_angle_increment_rad_ = scan.angle_increment;
  blind_seen_utime_ = scan.utime;
  if (blind_.count() == 0)
    blind_since_utime_ = -1;
  else if (blind_since_utime_ < 0)
    blind_since_utime_ = scan.utime;
}

std::string Mapper::blind_laser_reason() const {
  if (blind_since_utime_ < 0 ||
      static_cast<double>(blind_seen_utime_ - blind_since_utime_) < options_.blind_degraded_after_s * 1e6)
    return {};
  const auto runs = mapping::blind_runs(blind_.mask());
  if (runs.empty()) return {};
  // A covered window is one or two sectors; glass and dark surfaces at a
  // slant leave single beams here and there: the widest three say where.
  std::vector<mapping::BeamRun> widest(runs);
  const std::size_t shown = std::min<std::size_t>(3, widest.size());
  std::partial_sort(widest.begin(), widest.begin() + static_cast<std::ptrdiff_t>(shown), widest.end(),
                    [](const auto& a, const auto& b) { return a.last - a.first > b.last - b.first; });
  widest.resize(shown);
  std::sort(widest.begin(), widest.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  auto bearing = [this](std::size_t beam) {
    return blind_angle_min_rad_ + blind_angle_increment_rad_ * static_cast<double>(beam);
  };
  std::string sectors;
  for (const auto& run : widest) {
    sectors += sectors.empty() ? "" : ", ";
    sectors += run.first == run.last ? fmt::format("{:.2f}", bearing(run.first))
                                     : fmt::format("{:.2f}..{:.2f}", bearing(run.first), bearing(run.last));
  }
  const std::string more = runs.size() > shown ? fmt::format(" and {} more", runs.size() - shown) : "";
  // Either the laser cannot see there, or the map is off the world (a SLAM
  // that lost its frame draws walls where the laser looks into open space).
  return fmt::format(
      "laser blind on {} beams at {} rad{} (sensor frame): no echo where the map has walls (the window covered, or "
      "the map off the world)",
      blind_.count(), sectors, more);
}

const mapping::PolygonMap& Mapper::map() const {
  if (best_ >= 0) return particle_maps_.map(static_cast<std::size_t>(best_));
  return restored_ ? *restored_ : map_;
}

std::string Mapper::start_from(const mapping::TypedMultiPolygon& polygons) {
  if (counters_.scans_inserted > 0 || map_.scans_inserted() > 0 || restored_ || particle_maps_.size() > 0)
    return "a map is held already (a checkpoint was taken up, or scans went in)";
  mapping::PolygonMap map(options_.map);
  for (const auto& polygon : polygons) {
    const auto result = map.insert(polygon);
    counters_.failed_tile_updates += result.tiles_failed;
  }
  if (options_.pose_source == "slam") {
    restored_ = std::move(map);
    restored_any_epoch_ = true;
  } else {
    map_ = std::move(map);
  }
  mark_changed();
  return "";
}

mapping::ScanPolygonOptions Mapper::scan_options_for(const pex::laser_scan_t& scan) const {
  mapping::ScanPolygonOptions o = options_.scan;
  o.range_min_m = std::max<double>(o.range_min_m, scan.range_min);
  o.range_max_m = std::min<double>(o.range_max_m, scan.range_max);
  o.free_range_m = std::min(o.free_range_m, o.range_max_m);
  return o;
}

bool Mapper::on_slam_update(const pex::slam_update_t& update) {
  if (update.nparticles < 1 || static_cast<std::size_t>(update.nparticles) != update.particles.size())
    throw std::invalid_argument("SLAM_UPDATE has " + std::to_string(update.nparticles) + " particles in a field of " +
                                std::to_string(update.particles.size()));
  if (update.best < 0 || update.best >= update.nparticles)
    throw std::invalid_argument("SLAM_UPDATE best particle " + std::to_string(update.best) + " out of range");
  const int previous_best = best_;
  waiting_updates_.push_back(update);
  drain_waiting_updates();
  // An update older than the oldest scan held can never be applied.
  while (static_cast<int>(waiting_updates_.size()) > options_.max_pending_scans) {
    waiting_updates_.pop_front();
    ++counters_.updates_without_scan;
  }
  const bool switched = previous_best >= 0 && best_ != previous_best;
  if (switched) ++counters_.best_switches;
  return switched;
}

void Mapper::drain_waiting_updates() {
  while (!waiting_updates_.empty()) {
    bool applied = false;
    try {
      applied = apply_slam_update(waiting_updates_.front());
    } catch (const std::invalid_argument&) {
      waiting_updates_.pop_front();  // a refused update must not block the ones after it
      throw;
    }
    if (!applied) return;
    waiting_updates_.pop_front();
  }
}

bool Mapper::apply_slam_update(const pex::slam_update_t& update) {
  auto scan = std::find_if(pending_.begin(), pending_.end(),
                           [&](const pex::laser_scan_t& s) { return s.utime == update.scan_utime; });
  if (scan == pending_.end()) {
    if (!pending_.empty() && update.scan_utime < pending_.front().utime) {
      ++counters_.updates_without_scan;  // its scan has already left the buffer
      return true;
    }
    return false;  // wait for the scan
  }
  std::vector<particle_maps::ParticleState> particles;
  particles.reserve(update.particles.size());
  for (const auto& p : update.particles) particles.push_back({{p.x, p.y, p.theta}, p.parent});
  // Parents index the previous update's particles: only an update that follows
  // the one applied last may use them (a republish repeats its generation).
  const bool held = particle_maps_.size() > 0 || restored_;
  const bool continues = particle_maps_.size() > 0 && update.epoch == epoch_ &&
                         update.generation == generation_ + (update.republished ? 0 : 1);
  if (held && !continues) {
    if (update.epoch == epoch_ || (restored_ && restored_any_epoch_)) {
      // The same lineage, but the parents cannot be followed: the best map held
      // stands in for every particle (the map goes on; the particles' maps
      // differ again from the next scan on).
      const mapping::PolygonMap best = restored_ ? *restored_ : map();
      particle_maps_.reseed(best, particles.size());
      ++counters_.slam_resyncs;
    } else {
      particle_maps_.reseed(mapping::PolygonMap(options_.map), 0);  // another frame: start afresh
      ++counters_.slam_epoch_changes;
    }
  }
  if (!continues && particle_maps_.size() > 0)
    for (std::size_t i = 0; i < particles.size(); ++i) particles[i].parent = static_cast<int>(i);
  const mapping::ScanPolygonOptions scan_options = scan_options_for(*scan);
  const geometry::Pose2 mounting{scan->sensor_x, scan->sensor_y, scan->sensor_theta};
  // Which beams are blind, seen against the best particle's parent's map at
  // its pose: the same for every particle (it is the laser's). A first
  // update (or one in a new frame) has no map to see them against.
  const auto& best_particle = particles[static_cast<std::size_t>(update.best)];
  mapping::NoReturnExtents against_best;
  if (best_particle.parent >= 0 && static_cast<std::size_t>(best_particle.parent) < particle_maps_.size())
    against_best = mapping::no_return_extents_in(
        particle_maps_.map(static_cast<std::size_t>(best_particle.parent)), scan->ranges, scan->angle_min,
        scan->angle_increment, geometry::compose(best_particle.pose, mounting), scan_options);
  blind_.observe(scan->ranges, scan_options.range_min_m, scan_options.range_max_m, against_best.extent_m,
                 scan_options.free_range_m);
  note_blind_scan(*scan);
  const particle_maps::SensorScan sensor_scan{scan->ranges, scan->angle_min, scan->angle_increment, mounting,
                                              blind_.no_free_space_mask()};
  const auto result = particle_maps_.update(particles, sensor_scan, scan_options);
  if (!result.ok) throw std::invalid_argument("SLAM_UPDATE refused: " + result.error);
  restored_.reset();
  restored_any_epoch_ = false;
  epoch_ = update.epoch;
  if (!result.scan_inserted) ++counters_.scan_polygon_errors;
  if (static_cast<std::size_t>(update.best) < result.no_return_beams_stopped.size())
    counters_.no_return_beams_stopped += result.no_return_beams_stopped[static_cast<std::size_t>(update.best)];
  counters_.failed_tile_updates += result.insert_failures;
  ++counters_.slam_updates;
  ++counters_.scans_inserted;
  best_ = update.best;
  generation_ = update.generation;
  const auto& best = update.particles[static_cast<std::size_t>(update.best)];
  last_insert_pose_ = geometry::Pose2{best.x, best.y, best.theta};
  last_scan_utime_ = scan->utime;
  pending_.erase(pending_.begin(), scan + 1);  // older scans will get no update either
  mark_changed();
  return true;
}

void Mapper::on_scan(const pex::laser_scan_t& scan) {
  if (scan.nranges < 2 || static_cast<std::size_t>(scan.nranges) != scan.ranges.size())
    throw std::invalid_argument("scan has " + std::to_string(scan.nranges) + " ranges");
  if (scan.nranges > options_.scan.max_beams)
    throw std::invalid_argument("scan has more than max_beams ranges");
  if (scan.nintensities != 0 && scan.nintensities != scan.nranges)
    throw std::invalid_argument("intensities and ranges differ in size");
  if (!finite(scan.angle_min) || !finite(scan.angle_increment) || scan.angle_increment == 0.0f ||
      !finite(scan.range_min) || !finite(scan.range_max) || !finite(scan.sensor_x) ||
      !finite(scan.sensor_y) || !finite(scan.sensor_theta))
    throw std::invalid_argument("scan has non-finite or zero angle/range/sensor fields");
  if (options_.scan.min_returns > 0) {
    const auto limits = scan_options_for(scan);
    const int returns = mapping::count_returns(scan.ranges, limits.range_min_m, limits.range_max_m);
    if (returns < options_.scan.min_returns)
      throw std::invalid_argument("scan has " + std::to_string(returns) + " returns of " +
                                  std::to_string(scan.nranges) + " beams, fewer than min_returns " +
                                  std::to_string(options_.scan.min_returns) +
                                  ": a laser covered or dazzled; not mapped (its no-echo beams would clear walls)");
  }
  ++counters_.scans_received;
  pending_.push_back(scan);
  while (static_cast<int>(pending_.size()) > options_.max_pending_scans) {
    pending_.pop_front();
    if (options_.pose_source != "slam") ++counters_.scans_without_pose;
  }
  if (options_.pose_source == "slam") {
    // A scan is kept for the SLAM_UPDATE that names it (most scans get none).
    drain_waiting_updates();
    return;
  }
  process_pending();
}

void Mapper::on_pose(const TimedPose& pose) {
  poses_.add(pose);
  process_pending();
}

void Mapper::process_pending() {
  while (!pending_.empty()) {
    if (!try_insert(pending_.front())) return;  // waits for a newer pose
    pending_.pop_front();
  }
}

bool Mapper::try_insert(const pex::laser_scan_t& scan) {
  geometry::Pose2 robot;
  const auto lookup = poses_.pose_at(scan.utime, static_cast<std::int64_t>(options_.max_pose_gap_s * 1e6), robot);
  if (lookup == PoseBuffer::Lookup::kTooNew || lookup == PoseBuffer::Lookup::kEmpty) return false;
  if (lookup != PoseBuffer::Lookup::kOk) {
    ++counters_.scans_without_pose;
    return true;  // consumed: it will never get a pose
  }
  if (last_insert_pose_) {
    const double moved = std::hypot(robot.x_m - last_insert_pose_->x_m, robot.y_m - last_insert_pose_->y_m);
    const double turned = std::abs(geometry::wrap_angle(robot.theta_rad - last_insert_pose_->theta_rad));
    const bool due = options_.insert_max_interval_s > 0.0 && last_insert_scan_utime_ >= 0 &&
                     scan.utime - last_insert_scan_utime_ >= static_cast<std::int64_t>(options_.insert_max_interval_s * 1e6);
    if (moved < options_.insert_min_distance_m && turned < options_.insert_min_rotation_rad && !due) {
      ++counters_.scans_skipped_no_motion;
      return true;
    }
  }
  // Sensor pose in the map: the robot pose composed with the mounting.
  const geometry::Pose2 sensor = geometry::compose(robot, {scan.sensor_x, scan.sensor_y, scan.sensor_theta});
  const mapping::ScanPolygonOptions scan_options = scan_options_for(scan);
  int stopped = 0;
  const auto polygon = mapping::scan_to_polygon_in(map_, scan.ranges, scan.angle_min, scan.angle_increment, sensor,
                                                   scan_options, &stopped, &blind_);
  counters_.no_return_beams_stopped += stopped;
  note_blind_scan(scan);
  if (!polygon.ok) {
    ++counters_.scan_polygon_errors;
    return true;
  }
  const auto result = map_.insert(polygon.polygon);
  counters_.failed_tile_updates = map_.failed_tile_updates();
  ++counters_.scans_inserted;
  last_insert_pose_ = robot;
  last_insert_scan_utime_ = scan.utime;
  last_scan_utime_ = scan.utime;
  if (result.tiles_touched > 0) mark_changed();
  return true;
}

pex::polygon_map_t to_message(const mapping::TypedMultiPolygon& polygons) {
  pex::polygon_map_t msg{};
  msg.particle = -1;
  std::int32_t vertices = 0;
  for (std::size_t k = 0; k < polygons.size(); ++k) {
    const auto& p = polygons[k];
    auto add_ring = [&](const mapping::Ring& ring, const std::vector<mapping::EdgeType>& types, bool hole) {
      pex::polygon_ring_t r{};
      r.polygon = static_cast<std::int32_t>(k);
      r.hole = hole;
      r.nvertices = static_cast<std::int32_t>(types.size());
      for (std::size_t i = 0; i < types.size(); ++i) {
        r.x.push_back(ring[i].x());
        r.y.push_back(ring[i].y());
        // Braced copies: the LCM constants are declared but not defined (no odr-use).
        r.edge_type.push_back(types[i] == mapping::EdgeType::kObstacle
                                  ? std::int8_t{pex::polygon_ring_t::EDGE_OBSTACLE}
                                  : std::int8_t{pex::polygon_ring_t::EDGE_FRONTIER});
      }
      vertices += r.nvertices;
      msg.rings.push_back(std::move(r));
    };
    add_ring(p.geometry.outer(), p.edge_types[0], false);
    for (std::size_t h = 0; h < p.geometry.inners().size(); ++h)
      add_ring(p.geometry.inners()[h], p.edge_types[1 + h], true);
  }
  msg.nrings = static_cast<std::int32_t>(msg.rings.size());
  msg.vertex_count = vertices;
  msg.free_area_m2 = mapping::area(polygons);
  msg.obstacle_length_m = mapping::edge_length(polygons, mapping::EdgeType::kObstacle);
  msg.frontier_length_m = mapping::edge_length(polygons, mapping::EdgeType::kFrontier);
  return msg;
}

std::optional<pex::polygon_map_t> Mapper::map_message(std::int64_t now_utime) {
  if (dirty_) {
    const auto merged = map().planning_map();
    counters_.stale_planning_tiles = merged.stale_planning_tiles;
    take_merge(merged, message_, dirty_);
  }
  return stamped(message_, now_utime);
}

std::optional<pex::polygon_map_t> Mapper::free_space_message(std::int64_t now_utime) {
  if (free_space_dirty_) take_merge(map().free_space(), free_space_message_, free_space_dirty_);
  return stamped(free_space_message_, now_utime);
}

void Mapper::take_merge(const mapping::MergeResult& merged, std::optional<pex::polygon_map_t>& message, bool& dirty) {
  if (merged.ok) {
    message = to_message(merged.polygons);
    dirty = false;
  } else {
    ++counters_.merge_failures;  // keep the last good message; retried next time
  }
}

std::optional<pex::polygon_map_t> Mapper::stamped(std::optional<pex::polygon_map_t>& message,
                                                  std::int64_t now_utime) const {
  if (!message) return std::nullopt;
  message->utime = now_utime;
  message->scan_utime = last_scan_utime_;
  message->particle = best_;
  message->generation = best_ >= 0 ? generation_ : counters_.scans_inserted;
  message->scans_inserted = static_cast<std::int32_t>(counters_.scans_inserted);
  if (last_insert_pose_) {
    message->robot_x = last_insert_pose_->x_m;
    message->robot_y = last_insert_pose_->y_m;
    message->robot_theta = last_insert_pose_->theta_rad;
  }
  return message;
}

namespace {
constexpr std::string_view kCheckpointMagic = "PEXMAPR1";
constexpr std::uint32_t kCheckpointVersion = 1;
}  // namespace

std::string Mapper::checkpoint() const {
  archive::ByteWriter out;
  out.put_string(options_.pose_source);
  out.put<std::int64_t>(epoch_);
  out.put<std::int64_t>(generation_);
  out.put_bool(last_insert_pose_.has_value());
  const geometry::Pose2 pose = last_insert_pose_.value_or(geometry::Pose2{});
  out.put<double>(pose.x_m);
  out.put<double>(pose.y_m);
  out.put<double>(pose.theta_rad);
  out.put<std::int64_t>(last_insert_scan_utime_);
  out.put<std::int64_t>(last_scan_utime_);
  out.put<std::int64_t>(counters_.scans_inserted);
  mapping::write_polygon_map(out, map());
  return archive::seal(kCheckpointMagic, kCheckpointVersion, out.bytes());
}

std::string Mapper::restore(std::string_view checkpoint) {
  try {
    const std::string payload = archive::unseal(kCheckpointMagic, kCheckpointVersion, checkpoint);
    archive::ByteReader in(payload);
    const std::string source = in.get_string();
    if (source != options_.pose_source)
      return "the map was made with pose_source \"" + source + "\", the configuration has \"" +
             options_.pose_source + "\"";
    const auto epoch = in.get<std::int64_t>(), generation = in.get<std::int64_t>();
    const bool has_pose = in.get_bool();
    geometry::Pose2 pose;
    pose.x_m = in.get<double>();
    pose.y_m = in.get<double>();
    pose.theta_rad = in.get<double>();
    const auto last_insert_scan_utime = in.get<std::int64_t>(), last_scan_utime = in.get<std::int64_t>();
    const auto scans_inserted = in.get<std::int64_t>();
    mapping::PolygonMap map = mapping::read_polygon_map(in, options_.map);
    in.expect_end();
    // All read: take it up.
    if (options_.pose_source == "slam") {
      restored_ = std::move(map);
      epoch_ = epoch;
      generation_ = generation;
    } else {
      map_ = std::move(map);
    }
    last_insert_pose_ = has_pose ? std::optional(pose) : std::nullopt;
    last_insert_scan_utime_ = last_insert_scan_utime;
    last_scan_utime_ = last_scan_utime;
    counters_.scans_inserted = scans_inserted;
    mark_changed();
    return "";
  } catch (const archive::ArchiveError& e) {
    return e.what();
  }
}

}  // namespace pex::polygon_mapper
