#pragma once
// The explorer's adapter between LCM messages and the mission
// (planning/mission.hpp): checked inputs in, BASE_CMD and EXPLORE_STATE out,
// plans on a worker thread (or inline, for tests). No LCM calls here, so
// tests can drive it without a bus.
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pex/explore_state_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/mission_cmd_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/slam_update_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include "explorer_options.hpp"
#include "runtime/node.hpp"
#include "latency_stats.hpp"
#include "plan_worker.hpp"
#include "planning/driven_trail.hpp"
#include "planning/mission.hpp"

namespace pex::explorer {

struct ExplorerCounters {
  std::int64_t guard_limited_steps = 0;  // control steps whose forward speed the scan guard cut
  // Beams without a return the guard read as the planning map's wall they
  // run into (GuardScanOptions::map_walls_m).
  std::int64_t guard_map_wall_beams = 0;
  std::int64_t maps_accepted = 0;
  std::int64_t map_polygons_dropped = 0;
  std::int64_t map_rings_reoriented = 0;
  std::int64_t commands_applied = 0;
  // SLAM_UPDATEs that did not follow the last one (the best trail held stood
  // in for every particle's), and new SLAM epochs (the trails started afresh).
  std::int64_t trail_resyncs = 0;
  std::int64_t trail_epochs = 0;
  // Plans without the full margin sent with no trail: the map's particle
  // and generation had none here (no SLAM_UPDATE of it seen).
  std::int64_t tight_plans_without_trail = 0;
  // Plans failed because the keep-out could not be taken out of their map
  // (PlanResult::keep_out_failed; the mission counts them as failed plans).
  std::int64_t keep_out_failures = 0;
  // Times the guard held the robot still for guard_block_ms on its way
  // (one a hold), and those the mission replanned for (Mission::on_guard_block).
  std::int64_t guard_blocks = 0;
  std::int64_t guard_block_replans = 0;
  // Plans the map alone gave no way, planned again with the live view
  // (live_view_when_stuck_only).
  std::int64_t live_view_plans = 0;
  // Guard marks made (one a block with returns in the way: guard_mark_*),
  // and plans in which the marks left no way, planned again without them.
  std::int64_t guard_marks = 0;
  std::int64_t guard_marks_dropped_plans = 0;
  // Beams of the laser blind now (mapping::BlindBeams, seen against the
  // planning map's walls within guard_map_walls_m): the live view opens
  // nothing along them.
  std::int64_t blind_beams = 0;

  // By name, for DAEMON_STATUS (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    v.total("maps_accepted", maps_accepted);
    v.total("guard_limited_steps", guard_limited_steps);
    v.total("guard_map_wall_beams", guard_map_wall_beams);
    v.total("map_polygons_dropped", map_polygons_dropped);
    v.total("commands_applied", commands_applied);
    v.total("trail_resyncs", trail_resyncs);
    v.total("trail_epochs", trail_epochs);
    v.total("tight_plans_without_trail", tight_plans_without_trail);
    v.total("keep_out_failures", keep_out_failures);
    v.total("guard_blocks", guard_blocks);
    v.total("guard_block_replans", guard_block_replans);
    v.total("live_view_plans", live_view_plans);
    v.total("guard_marks", guard_marks);
    v.total("guard_marks_dropped_plans", guard_marks_dropped_plans);
    v.total("blind_beams", blind_beams);
  }
};

// The live view (planning/live_view.hpp) of a LIDAR_SCAN taken at `robot`
// (the laser's mounting applied), its beams without a return stopped at the
// walls of `map` (the planning map it is for; null: none), its blind beams
// (`blind`, per beam; empty: none) opening nothing; null when off or when it
// gives no polygon.
std::shared_ptr<const mapping::TypedMultiPolygon> live_view_of(const pex::laser_scan_t& scan,
                                                               const planning::Pose2& robot,
                                                               const planning::LiveViewOptions& options,
                                                               const mapping::TypedMultiPolygon* map,
                                                               std::span<const std::uint8_t> blind = {});

// A SLAM_UPDATE as the driven trails take it (planning/driven_trail.hpp).
planning::TrailUpdate trail_update_of(const pex::slam_update_t& msg);

// The way the robot drove in the frame of a map: the trail of the map's
// particle at the map's generation (MAP.particle, MAP.generation) from the
// SLAM_UPDATEs, or, for a map not made from SLAM particles (particle -1), the
// trail of the poses the explorer was given. One keeper for the explorer and
// pex-plan, so a replayed log plans as the robot did.
class TrailKeeper {
 public:
  explicit TrailKeeper(planning::DrivenTrailOptions options = {});
  // Throws std::invalid_argument (nothing changed) for an update the trails refuse.
  planning::DrivenTrails::Result on_slam_update(const pex::slam_update_t& msg);
  void on_pose(const planning::Pose2& pose);
  void on_map(const pex::polygon_map_t& msg);
  // Null when the map's particle and generation have no trail here.
  std::shared_ptr<const std::vector<mapping::Point>> trail_for_map() const;
  // Both trails (SLAM's best, the poses') across a restart, as bytes; taking
  // them up: "" when done, else why not (nothing changed). DrivenTrails::restore.
  std::string checkpoint() const;
  std::string restore(std::string_view checkpoint);

 private:
  planning::DrivenTrailOptions options_;
  planning::DrivenTrails slam_;
  planning::DrivenTrails poses_;
  std::int64_t pose_generation_ = 0;
  int map_particle_ = -1;
  std::int64_t map_generation_ = 0;
};

class ExplorerNode {
 public:
  enum class Planning { kWorkerThread, kInline };
  explicit ExplorerNode(ExplorerOptions options, Planning planning = Planning::kInline);

  // Inputs with their arrival time. A message refused (bad content) throws
  // std::invalid_argument with the reason, and changes nothing.
  void on_map(const pex::polygon_map_t& msg, std::int64_t now_utime);
  void on_pose(const pex::pose_t& msg, std::int64_t now_utime);
  // A SLAM_UPDATE: every particle's pose, for the way the robot drove in
  // each particle's map (tight plans go along it: PlanRequest::trail).
  void on_slam_update(const pex::slam_update_t& msg);
  // A LIDAR_SCAN: the laser is alive (the mission stops without scans), and
  // its returns bound the command (the scan guard, planning/scan_guard.hpp).
  void on_scan(const pex::laser_scan_t& msg, std::int64_t now_utime);
  // A MISSION_CMD. Returns "" when applied or already in effect, else why it
  // does not apply now (e.g. resume while not paused); a command that is not a
  // command is refused (std::invalid_argument).
  std::string on_command(const pex::mission_cmd_t& msg, std::int64_t now_utime);
  // Takes a finished plan from the worker (call when plan_fd() is readable).
  void on_plan_ready(std::int64_t now_utime);
  // The worker's eventfd (-1 with inline planning).
  int plan_fd() const { return worker_ ? worker_->fd() : -1; }

  // The mission's checkpoint as text, and taking one up (before the first
  // step): "" when restored, else why not (the mission then starts afresh).
  std::string checkpoint_text() const;
  std::string restore(const std::string& checkpoint_text);
  // The way the robot drove and the guard marks, likewise (a file of their
  // own, trail_checkpoint_file): a restarted explorer can still take the
  // robot back through a gap the map has shut since it drove through, and
  // does not send it into the glass that held it again. Both are in the
  // frame of the SLAM epoch the trail holds (a new one drops the marks as
  // ever); both are taken up, or neither. A file written before the marks
  // were in it (the trail alone) is taken up too.
  std::string trail_checkpoint() const;
  std::string restore_trails(const std::string& checkpoint);

  // One control step: the command to publish now. Never waits for a plan.
  pex::velocity_cmd_t step(std::int64_t now_utime);
  // The state after the last step.
  pex::explore_state_t state_message(std::int64_t now_utime) const;
  // A zero command (for shutdown).
  static pex::velocity_cmd_t stop_command(std::int64_t now_utime);

  const planning::MissionOutput& last_output() const { return last_; }
  const ExplorerCounters& counters() const { return counters_; }
  const ExplorerOptions& options() const { return options_; }
  const LatencyStats& plan_ms() const { return plan_ms_; }
  const LatencyStats& plan_cpu_ms() const { return plan_cpu_ms_; }
  const LatencyStats& control_ms() const { return control_ms_; }
  // The node's and the mission's counters and the latency percentiles (in
  // us), for DAEMON_STATUS and the exploration benchmark (runtime::Node::collect_counters).
  template <class Visitor>
  void visit_counters(Visitor& v) const {
    auto us = [](double ms) { return static_cast<std::int64_t>(std::llround(ms * 1000.0)); };
    counters_.visit_counters(v);
    v.total("plans", last_.plans);
    v.total("looks_around", last_.looks_around);
    v.total("backs_out", last_.backs_out);
    v.total("ways_in", last_.ways_in);
    v.total("goals_reached", last_.goals.reached);
    v.total("goals_seen", last_.goals.seen);
    v.total("goals_blocked", last_.goals.blocked);
    v.total("goals_no_progress", last_.goals.no_progress);
    v.total("goals_overdue", last_.goals.overdue);
    v.total("goals_came_back", last_.goals.came_back);
    v.total("phase", static_cast<std::int64_t>(last_.phase));
    v.total("plan_us_p50", us(plan_ms_.quantile(0.5)));
    v.total("plan_us_p99", us(plan_ms_.quantile(0.99)));
    v.total("plan_us_max", us(plan_ms_.quantile(1.0)));
    v.total("plan_cpu_us_p50", us(plan_cpu_ms_.quantile(0.5)));
    v.total("plan_cpu_us_p99", us(plan_cpu_ms_.quantile(0.99)));
    // The planner's CPU by what the plan was for (planning::PlanKind): which
    // kind of plan makes the p99 above.
    for (int k = 0; k < planning::kPlanKinds; ++k) {
      const std::string kind = planning::to_string(static_cast<planning::PlanKind>(k));
      v.total("plans_" + kind, plans_by_kind_[k]);
      v.total("plan_cpu_us_p99_" + kind, us(plan_cpu_ms_by_kind_[k].quantile(0.99)));
      v.total("plan_cpu_us_max_" + kind, us(plan_cpu_ms_by_kind_[k].quantile(1.0)));
    }
    v.total("control_us_p99", us(control_ms_.quantile(0.99)));
    v.total("control_us_max", us(control_ms_.quantile(1.0)));
    // The C-space's offset tiles (planning/inward_offset.hpp): taken from the
    // planning thread's cache, and computed.
    v.total("offset_tiles_kept", offset_tiles_.hits);
    v.total("offset_tiles_computed", offset_tiles_.misses);
    // The path graph's segment tests (planning/pruned_graph.hpp), the tour's:
    // answered from the last graph, tested again near a change of the map,
    // tested for pairs with a new node.
    v.total("graph_tests_kept", graph_tests_.kept);
    v.total("graph_tests_retested", graph_tests_.retested);
    v.total("graph_tests_new", graph_tests_.new_pairs);
  }

 private:
  // The newest scan's live view (planning/live_view.hpp) from `robot`, for
  // `map`; null when off or without a scan.
  std::shared_ptr<const mapping::TypedMultiPolygon> live_view_at(const planning::Pose2& robot,
                                                                 const mapping::TypedMultiPolygon* map) const;
  // What the mission's request leaves to the explorer: the live view, the
  // keep-out with the guard's marks, and for a tight plan the trail.
  void complete(planning::PlanRequest& request, std::int64_t now_utime);
  // A finished plan's failures the explorer counts (keep_out_failures), logged.
  void count_failures(const planning::PlanResult& result);
  // One control step's guard outcome: `held` when it stopped a robot the
  // follower wanted to drive forward on the arc of `curvature_per_m`. A
  // hold of guard_block_us while MOVING is told to the mission once
  // (Mission::on_guard_block), and what holds the robot is marked.
  void note_guard_hold(bool held, double curvature_per_m, std::int64_t now_utime);
  // A finished plan's wall and CPU time, in the totals and in its kind's.
  void add_plan_time(planning::PlanKind kind, double wall_ms, double cpu_ms);

  ExplorerOptions options_;
  planning::Mission mission_;
  std::unique_ptr<PlanWorker> worker_;
  planning::PlanCache inline_cache_;  // inline planning only: the worker has its own
  planning::OffsetTileCache::Counters offset_tiles_;  // of the cache that ran the newest plan
  planning::VisibilityCache::Counters graph_tests_;   // likewise
  planning::MissionOutput last_;
  ExplorerCounters counters_;
  // A map the overlay cannot cut fails every plan on it: a line each 10 s.
  runtime::RateLimitedLog failure_log_{std::chrono::seconds(10)};
  LatencyStats plan_ms_;
  LatencyStats plan_cpu_ms_;
  std::array<LatencyStats, planning::kPlanKinds> plan_cpu_ms_by_kind_;
  std::array<std::int64_t, planning::kPlanKinds> plans_by_kind_{};
  LatencyStats control_ms_;
  // The newest scan's returns in the robot's frame and when it came; none
  // yet: no bound (the mission itself stands without scans when
  // scan_timeout_ms watches them).
  std::vector<mapping::Point> scan_points_;
  std::optional<pex::laser_scan_t> last_scan_;  // for the live view of the next plan
  mapping::BlindBeams blind_;                   // the laser's, seen by the guard's map lookup
  std::vector<std::uint8_t> last_scan_blind_;   // its mask for last_scan_
  std::optional<std::int64_t> scan_utime_;
  TrailKeeper trails_;
  planning::ScanGuard guard_;                  // with its model of the robot's speed
  std::optional<std::int64_t> last_step_utime_;  // the previous control step
  std::optional<std::int64_t> guard_held_since_;  // the guard has held the robot still since (driving wanted)
  bool guard_hold_told_ = false;                  // this hold was told to the mission
  planning::GuardMarks guard_marks_;              // what held the robot, map frame (planning/guard_marks.hpp)
};

}  // namespace pex::explorer
