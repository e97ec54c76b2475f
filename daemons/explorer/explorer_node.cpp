#include "explorer_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "archive/byte_archive.hpp"
#include "mapping/scan_polygon.hpp"

namespace pex::explorer {

namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

ExplorerNode::ExplorerNode(ExplorerOptions options, Planning planning)
    : options_(std::move(options)),
      mission_(options_.mission),
      blind_(options_.blind_beams),
      guard_(options_.guard),
      guard_marks_(options_.guard_marks) {
  if (planning == Planning::kWorkerThread) worker_ = std::make_unique<PlanWorker>();
}

planning::TrailUpdate trail_update_of(const pex::slam_update_t& msg) {
  if (msg.nparticles < 0 || static_cast<std::size_t>(msg.nparticles) != msg.particles.size())
    throw std::invalid_argument("SLAM_UPDATE nparticles does not match its particles");
  planning::TrailUpdate u;
  u.epoch = msg.epoch;
  u.generation = msg.generation;
  u.republished = msg.republished;
  u.best = msg.best;
  u.particles.reserve(msg.particles.size());
  for (const auto& p : msg.particles) u.particles.push_back({{p.x, p.y, p.theta}, p.parent});
  return u;
}

TrailKeeper::TrailKeeper(planning::DrivenTrailOptions options) : options_(options), slam_(options), poses_(options) {}

planning::DrivenTrails::Result TrailKeeper::on_slam_update(const pex::slam_update_t& msg) {
  auto result = slam_.update(trail_update_of(msg));
  if (!result.ok) throw std::invalid_argument("SLAM_UPDATE refused for the trails: " + result.error);
  return result;
}

void TrailKeeper::on_pose(const planning::Pose2& pose) {
  // One particle, its own parent: the trail of the poses as they came.
  planning::TrailUpdate u;
  u.generation = pose_generation_++;
  u.particles.push_back({pose, 0});
  (void)poses_.update(u);  // finite (checked by the caller): never refused
}

void TrailKeeper::on_map(const pex::polygon_map_t& msg) {
  map_particle_ = msg.particle;
  map_generation_ = msg.generation;
}

std::shared_ptr<const std::vector<mapping::Point>> TrailKeeper::trail_for_map() const {
  std::optional<std::vector<mapping::Point>> trail =
      map_particle_ >= 0 ? slam_.trail(map_generation_, map_particle_) : poses_.best_trail();
  if (!trail || trail->empty()) return nullptr;
  return std::make_shared<const std::vector<mapping::Point>>(std::move(*trail));
}

namespace {
constexpr char kTrailKeeperMagic[] = "PEXTKEEP";
constexpr std::uint32_t kTrailKeeperVersion = 1;
}  // namespace

std::string TrailKeeper::checkpoint() const {
  archive::ByteWriter w;
  w.put_string(slam_.checkpoint());
  w.put_string(poses_.checkpoint());
  return archive::seal(kTrailKeeperMagic, kTrailKeeperVersion, w.bytes());
}

std::string TrailKeeper::restore(std::string_view checkpoint) {
  std::string slam, poses;
  try {
    const std::string payload = archive::unseal(kTrailKeeperMagic, kTrailKeeperVersion, checkpoint);
    archive::ByteReader r(payload);
    slam = r.get_string();
    poses = r.get_string();
    r.expect_end();
  } catch (const archive::ArchiveError& e) {
    return e.what();
  }
  // Each part may be empty (nothing held when it was written). Both are
  // taken up, or neither.
  planning::DrivenTrails slam_restored(options_), poses_restored(options_);
  if (!slam.empty())
    if (auto why = slam_restored.restore(slam); !why.empty()) return "SLAM's trail: " + why;
  if (!poses.empty())
    if (auto why = poses_restored.restore(poses); !why.empty()) return "the poses' trail: " + why;
  if (!slam.empty()) slam_ = std::move(slam_restored);
  if (!poses.empty()) {
    poses_ = std::move(poses_restored);
    pose_generation_ = *poses_.newest_generation() + 1;
  }
  return {};
}

namespace {
constexpr char kTrailsAndMarksMagic[] = "PEXTRMRK";
constexpr std::uint32_t kTrailsAndMarksVersion = 1;
}  // namespace

std::string ExplorerNode::trail_checkpoint() const {
  archive::ByteWriter w;
  w.put_string(trails_.checkpoint());
  w.put_string(guard_marks_.checkpoint());
  return archive::seal(kTrailsAndMarksMagic, kTrailsAndMarksVersion, w.bytes());
}

std::string ExplorerNode::restore_trails(const std::string& checkpoint) {
  std::string trails, marks;
  try {
    const std::string payload = archive::unseal(kTrailsAndMarksMagic, kTrailsAndMarksVersion, checkpoint);
    archive::ByteReader r(payload);
    trails = r.get_string();
    marks = r.get_string();
    r.expect_end();
  } catch (const archive::ArchiveError& e) {
    // The file of an explorer from before the marks: the trails alone.
    if (trails_.restore(checkpoint).empty()) return {};
    return e.what();
  }
  planning::GuardMarks marks_restored(options_.guard_marks);
  if (!marks.empty())
    if (auto why = marks_restored.restore(marks); !why.empty()) return "guard marks: " + why;
  if (auto why = trails_.restore(trails); !why.empty()) return why;
  guard_marks_ = std::move(marks_restored);
  return {};
}

void ExplorerNode::on_map(const pex::polygon_map_t& msg, std::int64_t now_utime) {
  DecodedMap decoded = decode_map(msg, options_.map);
  if (!decoded.ok) throw std::invalid_argument(decoded.error);
  trails_.on_map(msg);
  counters_.maps_accepted++;
  counters_.map_polygons_dropped += decoded.polygons_dropped;
  counters_.map_rings_reoriented += decoded.rings_reoriented;
  mission_.on_map(std::move(decoded.polygons), now_utime, msg.scan_utime);
}

void ExplorerNode::on_pose(const pex::pose_t& msg, std::int64_t now_utime) {
  if (!std::isfinite(msg.x) || !std::isfinite(msg.y) || !std::isfinite(msg.theta))
    throw std::invalid_argument("non-finite pose");
  mission_.on_pose(planning::Pose2{msg.x, msg.y, msg.theta}, now_utime);
  trails_.on_pose(planning::Pose2{msg.x, msg.y, msg.theta});
}

void ExplorerNode::on_slam_update(const pex::slam_update_t& msg) {
  const auto result = trails_.on_slam_update(msg);
  if (result.resynced) ++counters_.trail_resyncs;
  if (result.new_epoch) {
    ++counters_.trail_epochs;
    guard_marks_.clear();  // a new SLAM epoch is a new map frame
  }
}

void ExplorerNode::complete(planning::PlanRequest& request, std::int64_t now_utime) {
  request.live_view = live_view_at(request.pose, request.map.get());
  request.live_view_when_stuck_only = options_.live_view_when_stuck_only;
  request.keep_out = options_.keep_out;
  guard_marks_.expire(now_utime);
  if (auto marked = guard_marks_.with_keep_out(options_.keep_out)) {
    request.keep_out = std::move(marked);
    request.has_guard_marks = true;
    request.keep_out_without_marks = options_.keep_out;
  }
  if (request.tight && request.options.trail_corridor_m > 0.0) {
    request.trail = trails_.trail_for_map();
    if (!request.trail) ++counters_.tight_plans_without_trail;
  }
}

std::string ExplorerNode::checkpoint_text() const { return planning::to_text(mission_.checkpoint()); }

std::string ExplorerNode::restore(const std::string& text) {
  std::string why;
  const auto checkpoint = planning::checkpoint_from_text(text, &why);
  if (!checkpoint) return why;
  mission_.restore(*checkpoint);
  return {};
}

void ExplorerNode::on_scan(const pex::laser_scan_t& msg, std::int64_t now_utime) {
  if (msg.nranges <= 0 || static_cast<std::size_t>(msg.nranges) != msg.ranges.size())
    throw std::invalid_argument("scan without ranges");
  if (msg.ranges.size() > options_.max_beams)
    throw std::invalid_argument("scan has " + std::to_string(msg.ranges.size()) + " beams, more than max_beams " +
                                std::to_string(options_.max_beams));
  if (!std::isfinite(msg.angle_min) || !std::isfinite(msg.angle_increment) || !std::isfinite(msg.sensor_x) ||
      !std::isfinite(msg.sensor_y) || !std::isfinite(msg.sensor_theta))
    throw std::invalid_argument("scan geometry is not finite");
  if (options_.min_scan_returns > 0) {
    const int returns = mapping::count_returns(msg.ranges, msg.range_min, msg.range_max);
    if (returns < options_.min_scan_returns)
      throw std::invalid_argument("scan has " + std::to_string(returns) + " returns of " +
                                  std::to_string(msg.ranges.size()) + " beams, fewer than min_scan_returns " +
                                  std::to_string(options_.min_scan_returns) +
                                  ": a laser covered or dazzled is no view; the robot stops as without scans");
  }
  // Returns in the robot's frame (the laser's mounting), for the guard; a
  // beam without a return reads the planning map's wall it runs into, if
  // one is near (a laser blind in a sector sees nothing there).
  const geometry::Pose2 mounting{msg.sensor_x, msg.sensor_y, msg.sensor_theta};
  std::vector<float> with_walls;
  std::span<const float> guard_ranges = msg.ranges;
  if (options_.guard_scan.map_walls_m > 0.0 && mission_.map() && mission_.pose()) {
    int filled = 0;
    with_walls = planning::ranges_with_map_walls(msg.ranges, msg.angle_min, msg.angle_increment, msg.range_min,
                                                 msg.range_max, geometry::compose(*mission_.pose(), mounting),
                                                 *mission_.map(), options_.guard_scan.map_walls_m, &filled, &blind_);
    counters_.blind_beams = blind_.count();
    if (filled > 0) guard_ranges = with_walls;
    counters_.guard_map_wall_beams += filled;
  }
  scan_points_ = planning::guard_points(guard_ranges, msg.angle_min, msg.angle_increment, msg.range_min, msg.range_max,
                                        mounting, options_.guard_scan);
  scan_utime_ = now_utime;
  last_scan_ = msg;
  last_scan_blind_.assign(blind_.no_free_space_mask().begin(), blind_.no_free_space_mask().end());
  mission_.on_scan(now_utime);
}

std::string ExplorerNode::on_command(const pex::mission_cmd_t& msg, std::int64_t now_utime) {
  if (msg.command < pex::mission_cmd_t::CMD_START || msg.command > pex::mission_cmd_t::CMD_STOP)
    throw std::invalid_argument("unknown mission command " + std::to_string(msg.command));
  const auto command = static_cast<planning::MissionCommand>(msg.command);
  std::string why = mission_.on_command(command, now_utime);
  if (why.empty()) counters_.commands_applied++;
  return why;
}

void ExplorerNode::on_plan_ready(std::int64_t now_utime) {
  if (!worker_) return;
  if (auto timed = worker_->take_result()) {
    add_plan_time(timed->kind, timed->compute_ms, timed->compute_cpu_ms);
    offset_tiles_ = timed->offset_tiles;
    graph_tests_ = timed->graph_tests;
    count_failures(timed->result);
    mission_.on_plan(timed->result, now_utime);
  }
}

void ExplorerNode::count_failures(const planning::PlanResult& result) {
  if (result.live_view_used) ++counters_.live_view_plans;
  if (result.guard_marks_dropped) ++counters_.guard_marks_dropped_plans;
  if (!result.keep_out_failed) return;
  ++counters_.keep_out_failures;
  failure_log_.log(spdlog::level::err, "keep_out",
                   "plan failed (" + std::to_string(counters_.keep_out_failures) + " so far): " + result.plan.error);
}

void ExplorerNode::add_plan_time(planning::PlanKind kind, double wall_ms, double cpu_ms) {
  plan_ms_.add(wall_ms);
  plan_cpu_ms_.add(cpu_ms);
  auto& of_kind = plan_cpu_ms_by_kind_[static_cast<std::size_t>(kind)];
  of_kind.add(cpu_ms);
  ++plans_by_kind_[static_cast<std::size_t>(kind)];
}

pex::velocity_cmd_t ExplorerNode::step(std::int64_t now_utime) {
  const auto started = std::chrono::steady_clock::now();
  if (worker_) {
    last_ = mission_.step(now_utime);
    if (last_.plan_request) {
      complete(*last_.plan_request, now_utime);
      worker_->submit(std::move(*last_.plan_request));
    }
  } else {
    // Inline: the plan runs here (tests); its time is measured apart.
    last_ = planning::step_with_inline_planning(mission_, now_utime, [this, now_utime](planning::PlanRequest request) {
      complete(request, now_utime);
      const auto plan_started = std::chrono::steady_clock::now();
      const double cpu_started = thread_cpu_ms();
      auto result = planning::compute_plan(request, &inline_cache_);
      add_plan_time(planning::plan_kind(request), ms_since(plan_started), thread_cpu_ms() - cpu_started);
      offset_tiles_ = inline_cache_.offsets.counters();
      graph_tests_ = inline_cache_.visibility_counters();
      count_failures(result);
      return result;
    });
  }
  last_.plan_request.reset();
  if (worker_) control_ms_.add(ms_since(started));
  pex::velocity_cmd_t cmd = stop_command(now_utime);
  cmd.v = last_.command.v_mps;
  cmd.omega = last_.command.omega_radps;
  const double step_s = last_step_utime_ ? std::max<std::int64_t>(0, now_utime - *last_step_utime_) * 1e-6 : 0.0;
  last_step_utime_ = now_utime;
  if (options_.scan_guard && scan_utime_) {
    const double since_scan_s = std::max<std::int64_t>(0, now_utime - *scan_utime_) * 1e-6;
    const auto guarded = guard_.command(scan_points_, cmd.v, cmd.omega, since_scan_s, step_s);
    if (guarded.limited) ++counters_.guard_limited_steps;
    note_guard_hold(cmd.v > 0.0 && guarded.limited && guarded.v_mps <= 0.0, cmd.v > 0.0 ? cmd.omega / cmd.v : 0.0,
                    now_utime);
    cmd.v = guarded.v_mps;
    cmd.omega = guarded.omega_radps;
  } else {
    guard_.sent(cmd.v, step_s);
  }
  return cmd;
}

void ExplorerNode::note_guard_hold(bool held, double curvature_per_m, std::int64_t now_utime) {
  if (!held || last_.phase != planning::Phase::kMoving) {
    guard_held_since_.reset();
    return;
  }
  if (!guard_held_since_) {
    guard_held_since_ = now_utime;
    guard_hold_told_ = false;
  }
  if (guard_hold_told_ || options_.guard_block_us <= 0 || now_utime - *guard_held_since_ < options_.guard_block_us)
    return;
  guard_hold_told_ = true;  // once a hold: the mission's replan moves the robot on, or the goal's time runs out
  ++counters_.guard_blocks;
  // Marked before the replan is asked for, so that the replan goes round it.
  const auto holding =
      planning::holding_points(scan_points_, curvature_per_m, options_.guard.body_radius_m, options_.guard_marks);
  if (mission_.pose() && guard_marks_.add(holding, *mission_.pose(), now_utime)) ++counters_.guard_marks;
  if (mission_.on_guard_block(now_utime)) ++counters_.guard_block_replans;
}

std::shared_ptr<const mapping::TypedMultiPolygon> live_view_of(const pex::laser_scan_t& scan,
                                                               const planning::Pose2& robot,
                                                               const planning::LiveViewOptions& options,
                                                               const mapping::TypedMultiPolygon* map,
                                                               std::span<const std::uint8_t> blind) {
  if (!(options.range_m > 0.0)) return nullptr;
  // The sensor's pose in the map frame: the robot's, composed with the mounting.
  const geometry::Pose2 sensor = geometry::compose(robot, {scan.sensor_x, scan.sensor_y, scan.sensor_theta});
  auto view = planning::live_view(scan.ranges, scan.angle_min, scan.angle_increment, scan.range_min, sensor, options,
                                  map, blind);
  if (view.empty()) return nullptr;
  return std::make_shared<const mapping::TypedMultiPolygon>(std::move(view));
}

std::shared_ptr<const mapping::TypedMultiPolygon> ExplorerNode::live_view_at(
    const planning::Pose2& robot, const mapping::TypedMultiPolygon* map) const {
  return last_scan_ ? live_view_of(*last_scan_, robot, options_.live_view, map, last_scan_blind_) : nullptr;
}

pex::velocity_cmd_t ExplorerNode::stop_command(std::int64_t now_utime) {
  pex::velocity_cmd_t cmd{};
  cmd.utime = now_utime;
  cmd.v = 0.0;
  cmd.omega = 0.0;
  cmd.source = "explorer";
  return cmd;
}

pex::explore_state_t ExplorerNode::state_message(std::int64_t now_utime) const {
  pex::explore_state_t s{};
  s.utime = now_utime;
  s.phase = static_cast<std::int8_t>(last_.phase);
  s.status = last_.degraded ? "DEGRADED: " + last_.status : last_.status;
  s.strategy = planning::to_string(options_.mission.planner.strategy);
  s.has_goal = last_.goal.has_value();
  if (last_.goal) {
    s.goal_x = last_.goal->x();
    s.goal_y = last_.goal->y();
  }
  s.goal_candidates = last_.goal_candidates;
  for (const auto& p : last_.path) {
    s.path_x.push_back(p.x());
    s.path_y.push_back(p.y());
  }
  s.npath = static_cast<std::int32_t>(s.path_x.size());
  s.explored_area_m2 = last_.explored_area_m2;
  s.distance_travelled_m = last_.distance_travelled_m;
  s.mission_time_s = last_.mission_time_s;
  s.goals_reached = static_cast<std::int32_t>(last_.goals.reached);
  s.goals_given_up = static_cast<std::int32_t>(last_.goals.given_up());
  s.plans = static_cast<std::int32_t>(last_.plans);
  for (const auto& f : last_.frontiers) {
    s.frontier_x.push_back(f.position.x());
    s.frontier_y.push_back(f.position.y());
    s.frontier_reason.push_back(static_cast<std::int8_t>(f.reason));
  }
  s.nfrontiers = static_cast<std::int32_t>(s.frontier_x.size());
  return s;
}

}  // namespace pex::explorer
