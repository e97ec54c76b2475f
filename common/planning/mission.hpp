#pragma once
// The exploration mission as a pure state machine (paper, Algorithm 1: repeat
// "select a goal on the frontiers, go there" until no frontier is left).
//
//   IDLE       no map or no pose yet
//   SELECTING  plan on the newest map, pick the best candidate
//   MOVING     follow the path; replan every replan_period_us:
//                goal reached                -> SELECTING (after a newer map)
//                goal gone (frontier seen)   -> SELECTING
//                goal unreachable / no progress -> blacklist it, SELECTING
//                a clearly better goal       -> switch to it
//   DONE       no reachable candidate left (confirmed on done_confirmations maps),
//              also without the clearance margin (tight_fallback)
//   FAILED     max_consecutive_failures goals given up or plans failed in a row
//
// Stale inputs (pose or map older than its timeout) stop the robot and set
// `degraded` without changing the phase; the mission resumes when they are
// fresh again. No clock, no I/O: time comes in with every call.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "planning/exploration_planner.hpp"
#include "planning/path_follower.hpp"

namespace pex::planning {

// Values match pex::explore_state_t's PHASE_* constants.
enum class Phase : std::int8_t { kIdle = 0, kSelecting = 1, kMoving = 2, kDone = 3, kFailed = 4 };
const char* to_string(Phase phase);

struct MissionOptions {
  PlannerOptions planner;
  FollowerOptions follower;  // follower.goal_tolerance_m decides "goal reached"
  std::int64_t replan_period_us = 1'000'000;
  std::int64_t pose_timeout_us = 500'000;
  std::int64_t map_timeout_us = 5'000'000;
  // After a replan, the candidate nearest the current goal within this radius
  // is the same goal (frontiers move as the robot sees more).
  double goal_match_radius_m = 1.5;
  // While moving, switch to another candidate only if it is this much cheaper.
  double switch_margin_m = 1.0;
  // Give a goal up if neither its path has become progress_min_m shorter nor
  // the goal has moved on by progress_min_m (its frontier receding) within
  // progress_timeout_us.
  std::int64_t progress_timeout_us = 20'000'000;
  double progress_min_m = 0.3;
  int max_consecutive_failures = 5;
  // Plans on this many different maps in a row must find no candidate
  // before the mission is DONE (a map may lag behind the robot).
  int done_confirmations = 2;
  // Pose jumps longer than this (a SLAM correction) do not count as travel.
  double max_travel_step_m = 1.0;
  // When no candidate is reachable but some have no path or no C-space point
  // near them, plan once more without planner.cspace.clearance_margin_m: a
  // door that looks narrower on a newer map may still let the robot through.
  bool tight_fallback = true;
};

struct MissionOutput {
  Phase phase = Phase::kIdle;
  std::string status;           // why the phase is what it is
  bool degraded = false;        // an input is stale: the robot is stopped
  std::string degraded_reason;  // "pose is stale" / "map is stale" (no numbers: stable while it lasts)
  VelocityCommand command;      // zero unless MOVING and not degraded
  std::optional<Point> goal;
  std::vector<Point> path;      // robot to goal
  int goal_candidates = 0;      // candidates in the C-space in the last plan
  double explored_area_m2 = 0.0;
  double distance_travelled_m = 0.0;
  bool planned = false;         // this step ran the planner
  PlanStats plan_stats;         // of the last plan
};

class Mission {
 public:
  explicit Mission(MissionOptions options = {});

  // Inputs, with the time they arrived (us). A map replaces the previous one.
  void on_map(TypedMultiPolygon map, std::int64_t utime);
  void on_pose(const Pose2& pose, std::int64_t utime);

  // One control step at `now_utime`; call at the command rate.
  MissionOutput step(std::int64_t now_utime);

  Phase phase() const { return phase_; }
  const std::vector<Point>& blacklist() const { return blacklist_; }
  const std::vector<Point>& visited_goals() const { return visited_; }
  const MissionOptions& options() const { return options_; }

 private:
  Plan run_planner(std::int64_t now_utime, bool tight);
  // Plans (with the tight fallback) and selects a goal from the plan.
  void plan_and_select(std::int64_t now_utime);
  void select(const Plan& plan, std::int64_t now_utime);
  void replan_while_moving(std::int64_t now_utime);
  void give_up_goal(const std::string& why);
  void enter(Phase phase, std::string status);
  MissionOutput output(bool planned) const;

  MissionOptions options_;
  PathFollower follower_;
  Phase phase_ = Phase::kIdle;
  std::string status_ = "waiting for a map and a pose";
  bool degraded_ = false;

  std::optional<TypedMultiPolygon> map_;
  std::int64_t map_utime_ = 0;
  double explored_area_m2_ = 0.0;
  std::optional<Pose2> pose_;
  std::int64_t pose_utime_ = 0;
  double travelled_m_ = 0.0;

  std::int64_t last_step_utime_ = -1;
  std::int64_t last_plan_utime_ = -1;
  std::int64_t last_plan_map_utime_ = -1;
  std::int64_t select_after_map_utime_ = -1;  // SELECTING waits for a map newer than this
  std::int64_t last_empty_map_utime_ = -1;
  int empty_plans_ = 0;
  int goal_failures_ = 0;
  int plan_failures_ = 0;

  std::optional<Point> goal_;
  bool goal_tight_ = false;  // the goal was planned without the clearance margin
  double best_remaining_m_ = 0.0;
  Point progress_goal_;  // where the goal was at the last progress
  std::int64_t progress_utime_ = 0;
  int goal_candidates_ = 0;
  PlanStats plan_stats_;
  std::vector<Point> blacklist_;  // goals given up and goals reached
  std::vector<Point> visited_;
};

}  // namespace pex::planning
