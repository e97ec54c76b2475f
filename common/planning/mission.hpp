#pragma once
// The exploration mission as a pure state machine (paper, Algorithm 1: repeat
// "select a goal on the frontiers, go there" until no frontier is left), with
// the operator's commands on top.
//
//   WAITING_START  autostart off: nothing moves until `start`
//   IDLE           no map or no pose yet
//   SELECTING      a plan on the newest map picks the goal (strategy: greedy or tour)
//   MOVING         follow the path; replan every replan_period_us. The goal is
//                  kept (no switching) until it is
//                    reached (there, and turned to face its frontier point)
//                                                  -> SELECTING (after a newer map)
//                    seen (its frontier is gone from two maps in a row)
//                                                  -> SELECTING; seen where a
//                      goal was seen before: blacklisted (came back)
//                    blocked (no path any more)    -> blacklisted, SELECTING
//                    given up: no progress (the path not shorter and the
//                      frontier not moved on for progress_timeout_us), or
//                      overdue (progressing, but not reached within progress
//                      timeout + 4 x its path's driving time: a frontier that
//                      keeps receding ahead) -> blacklisted, SELECTING
//                  each outcome counted in GoalOutcomes.
//   DONE           no frontier left, or only frontiers already visited (the robot
//                  stood at their goal facing them: driving cannot show more);
//                  confirmed on done_confirmations maps
//   DONE_WITH_UNREACHABLE  frontiers are left that the robot could not get to
//                  (no path, too narrow, given up); each listed with why. Before
//                  it, still SELECTING: a turn on the spot (look_around) and, if
//                  the robot is in a lesser piece of the C-space, a way back
//                  along where it came from (back_out_m), planning all along
//   FAILED         max_consecutive_failures goals given up in a row for want
//                  of progress (the robot could not get closer: stuck) or
//                  overdue (it chases frontiers it never reaches), or plans
//                  failed in a row; goals blocked by a newer map are given up
//                  and blacklisted but are no failure of the robot, nor are
//                  goals given up again in the round that retries them, unless
//                  the robot stood (did not get 1 m from where it took the goal)
//   PAUSED         `pause`: wheels stopped, goal and state kept; `resume` goes on
//   HOMING / HOME  `home`: back to the pose the mission started at, then stopped;
//                  with no path home with the margin, planned without it and
//                  along the way the robot drove (PlanRequest::trail)
//   STOPPED        `stop`: wheels stopped until `start`
//
// Planning never runs inside step(): step() asks for a plan (MissionOutput::
// plan_request) and the caller runs compute_plan() wherever it likes (the
// explorer: a worker thread) and hands the result back with on_plan(). Until
// then the robot keeps following its last path, so the control step never
// waits for a plan. step_with_inline_planning() does both at once for tests
// and offline tools.
//
// Stale inputs (pose, map or laser scans older than their timeout) stop the robot and set
// `degraded` without changing the phase; the mission resumes when they are
// fresh again. No clock, no I/O: time comes in with every call.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "planning/exploration_planner.hpp"
#include "planning/path_follower.hpp"

namespace pex::planning {

// Values match pex::explore_state_t's PHASE_* constants.
enum class Phase : std::int8_t {
  kIdle = 0,
  kSelecting = 1,
  kMoving = 2,
  kDone = 3,
  kFailed = 4,
  kDoneWithUnreachable = 5,
  kWaitingStart = 6,
  kPaused = 7,
  kHoming = 8,
  kHome = 9,
  kStopped = 10,
};
const char* to_string(Phase phase);
// The mission has ended on its own (DONE, DONE_WITH_UNREACHABLE, FAILED).
bool is_finished(Phase phase);

// Values match pex::mission_cmd_t's CMD_* constants.
enum class MissionCommand : std::int8_t { kStart = 1, kPause = 2, kResume = 3, kHome = 4, kStop = 5 };
const char* to_string(MissionCommand command);

// Values match pex::explore_state_t's FRONTIER_* constants.
enum class FrontierReason : std::int8_t {
  kReachable = 0,
  kNoPath = 1,
  kTooNarrow = 2,
  kGivenUp = 3,
  kVisited = 4,
  kOutOfView = 5,
  kPocket = 6,
  kEnclosed = 7,
  kBehindNarrowGap = 8,
};

struct FrontierLeft {
  Point position;  // the candidate (in the C-space), or the frontier point when it has no C-space point
  FrontierReason reason = FrontierReason::kReachable;
};

struct MissionOptions {
  PlannerOptions planner;
  FollowerOptions follower;  // follower.goal_tolerance_m decides "goal reached"
  // Explore as soon as map and pose are there; off: wait for a start command.
  bool autostart = true;
  std::int64_t replan_period_us = 1'000'000;
  std::int64_t pose_timeout_us = 500'000;
  std::int64_t map_timeout_us = 5'000'000;
  // No laser scan for this long: stop, degraded (no driving blind: the map
  // and the pose may still come, from the last scans and from odometry).
  // 0 = scans are not watched (the mission is not told about them).
  std::int64_t scan_timeout_us = 0;
  // A plan asked for and not answered within this time is asked for again
  // (the answer to the old request is then ignored).
  std::int64_t plan_timeout_us = 5'000'000;
  // After a replan, the candidate nearest the current goal within this radius
  // is the same goal (frontiers move as the robot sees more); so is one for a
  // frontier point this near the goal's (its approach point may have moved).
  double goal_match_radius_m = 1.5;
  // Give a goal up if neither its path has become progress_min_m shorter nor
  // the goal has moved on by progress_min_m (its frontier receding) within
  // progress_timeout_us.
  std::int64_t progress_timeout_us = 20'000'000;
  double progress_min_m = 0.3;
  int max_consecutive_failures = 5;
  // Plans on this many different maps in a row must find no candidate
  // before the mission is DONE (a map may lag behind the robot).
  int done_confirmations = 2;
  // At a goal the robot turns to face the goal's frontier point until it is
  // within this angle (the laser sees 270 degrees, not what is behind it): a
  // goal is reached when the robot is there and looking. 0: no turning.
  double look_tolerance_rad = 0.5;
  // Pose jumps longer than this (a SLAM correction) do not count as travel.
  double max_travel_step_m = 1.0;
  // When no candidate is reachable but some have no path or no C-space point
  // near them, plan once more without planner.cspace.clearance_margin_m, and
  // along the way the robot drove (PlanRequest::trail): a door that looks
  // narrower on a newer map may still let the robot through.
  bool tight_fallback = true;
  // Before it ends DONE_WITH_UNREACHABLE the robot turns once on the spot,
  // planning as it turns (the explorer unites the newest scan into each plan:
  // planning/live_view.hpp), unless it looked around within 1 m of here
  // already: a door closed in the map by a band, out of the laser's sight
  // where the robot stopped, opens when the laser sees through it. Bounded by
  // look_around_max_us (a robot that cannot turn ends the look then).
  bool look_around = true;
  std::int64_t look_around_max_us = 15'000'000;
  // Then, before it ends DONE_WITH_UNREACHABLE, the robot drives back the way
  // it came, up to this far, planning as it goes; once until it next has a
  // goal. A door it came through on a plan without the margin can look too
  // narrow on the map made from inside (its frame seen from there), and
  // shut it in with the rest of the building unexplored
  // (pex-bench-strategies, tour: intel and fr079 ended at coverage 0.49-0.58
  // in a nook). The way it drove is the way it fits. Not again within 2 m of
  // where the last way back began. 0: off.
  double back_out_m = 20.0;
  // A way in: after an approach point is reached, a goal at its frontier's
  // own place that the plan with the full margin does not reach is planned
  // and followed with this margin (at most clearance_margin_m; 0 as the tight
  // fallback). Part of the margin is kept: such a way runs through a gap
  // about the robot's width (docs/exploration.md, "Frontiers seen through a
  // door": the way in).
  double way_in_margin_m = 0.025;
  // A goal's path the scan guard holds the robot on (on_guard_block: it ran
  // into something the map does not hold) starts its progress anew, this many
  // times a goal at most. The explorer marks what held it (guard_marks.hpp:
  // glass the map has as free never gets into the maps), and the path round
  // it is longer than the one the robot had: measured against the old one,
  // every detour was "no progress". Clean glass is the case that made it
  // (docs/exploration.md, "Held by the guard", "Guard marks"): a pane is
  // closed a piece at a time, each piece one hold, and office floors with
  // glass fronts ended FAILED, five goals behind the glass given up in a
  // row. 0: off.
  int max_guard_blocks_per_goal = 8;
};

// How goals ended (counted over the mission).
struct GoalOutcomes {
  std::int64_t reached = 0;
  std::int64_t seen = 0;         // its frontier was explored before the robot got there
  std::int64_t blocked = 0;      // no path to it any more: blacklisted
  std::int64_t no_progress = 0;  // neither path nor frontier moved on for progress_timeout_us: blacklisted
  // Progressing, yet not reached by its deadline (Mission::deadline_for): on
  // open ground, mostly a goal whose frontier receded ahead of the robot
  // while it explored on the way: blacklisted.
  std::int64_t overdue = 0;
  // Seen where a goal was seen before: a frontier the maps show and drop by
  // turns (a passage SLAM's corrections open and close, a sliver at a glass
  // gap), not one the robot clears by driving there: blacklisted.
  std::int64_t came_back = 0;
  std::int64_t given_up() const { return blocked + no_progress + overdue + came_back; }
};

// What the planner is asked: everything it needs, copied, so it can run on
// another thread while the mission goes on.
struct PlanRequest {
  std::uint64_t id = 0;
  std::shared_ptr<const TypedMultiPolygon> map;
  std::int64_t map_utime = 0;
  Pose2 pose;
  std::vector<Point> blacklist;
  PlannerOptions options;      // clearance margin already dropped when tight
  bool tight = false;          // planned without the clearance margin
  std::optional<Point> home;   // set: a path to this point, not frontier goals
  std::optional<GoalFocus> focus;  // the goal being followed: its path is wanted in the plan
  // The newest scan's free space near the robot (live_view.hpp), united into
  // `map` before planning; null or empty: the map alone. The mission leaves it
  // empty; the explorer adds it from the newest LIDAR_SCAN.
  std::shared_ptr<const TypedMultiPolygon> live_view;
  // The live view only when the map alone gives this plan nothing to drive
  // to (no goal; for a follow plan no path to the goal followed; no way
  // home): a live view also sees through glass at a slant, and united into
  // every plan it reopened the pieces of a pane the map had from looking at
  // it head-on, so the path to a goal behind a glass front swapped between
  // the glass and the door from one plan to the next (docs/exploration.md,
  // "Glass: the live view"). What it is for, a door the map shut by a band,
  // is a plan with no way through. False: every plan has it.
  bool live_view_when_stuck_only = false;
  // The way the robot drove, oldest point first, in the map's frame (the
  // map's particle's trail: driven_trail.hpp). A tight plan unites its
  // corridor (options.trail_corridor_m) into the C-space; null or empty:
  // none. The mission leaves it empty; the explorer adds it to tight requests.
  std::shared_ptr<const std::vector<Point>> trail;
  // Keep-out lines and areas (keep_out.hpp), in the map frame: taken out of
  // the map and of its live view before planning. Null or empty: none. The
  // mission leaves it empty; the explorer adds its keep_out_file's.
  std::shared_ptr<const TypedMultiPolygon> keep_out;
  // keep_out holds the scan guard's marks (guard_marks.hpp: what held the
  // robot, glass the map has as free), and this is keep_out without them: a
  // plan in which the marks leave no goal (or no way home) is planned again
  // on it (a person who stood in a door and has gone). False: no marks.
  bool has_guard_marks = false;
  std::shared_ptr<const TypedMultiPolygon> keep_out_without_marks;
};

// What a request is for, as the explorer counts plan cost by it: a path
// home; a plan without (part of) the clearance margin, along the driven
// trail (tight fallbacks and ways in, whose C-space is not the cached one);
// one that follows the goal in hand; one that selects a goal.
enum class PlanKind : std::int8_t { kSelect, kFollow, kTight, kHome };
inline constexpr int kPlanKinds = 4;
PlanKind plan_kind(const PlanRequest& request);
const char* to_string(PlanKind kind);

struct PlanResult {
  std::uint64_t id = 0;  // the request's
  Plan plan;
  // The request's keep-out could not be taken out of its map (the overlay
  // failed): the plan failed rather than plan on the map without it.
  bool keep_out_failed = false;
  // PlanRequest::live_view_when_stuck_only: the map alone gave no way, and
  // this plan is the one with the live view.
  bool live_view_used = false;
  // PlanRequest::has_guard_marks: the marks left no way, and this plan is
  // the one without them.
  bool guard_marks_dropped = false;
};

// Whether `plan` gives the robot somewhere to drive: a goal, or with `focus`
// (a follow plan) a reachable candidate matching the goal followed. A home
// plan's one candidate is home.
bool gives_a_way(const Plan& plan, const GoalFocus* focus);

// Runs the request: plan_exploration(), or plan_path_to() for `home`. The
// result is a function of the request; `cache` (may be null: one per
// planning thread) keeps what the planner can reuse between requests.
PlanResult compute_plan(const PlanRequest& request, PlanCache* cache = nullptr);

struct MissionOutput {
  Phase phase = Phase::kIdle;
  std::string status;           // why the phase is what it is
  bool degraded = false;        // an input is stale: the robot is stopped
  std::string degraded_reason;  // "pose is stale" / "map is stale" (no numbers: stable while it lasts)
  VelocityCommand command;      // zero unless MOVING or HOMING and not degraded
  std::optional<Point> goal;
  std::vector<Point> path;      // robot to goal
  int goal_candidates = 0;      // candidates in the C-space in the last plan
  std::vector<FrontierLeft> frontiers;  // every candidate of the last plan, with why it is left
  double explored_area_m2 = 0.0;
  double distance_travelled_m = 0.0;
  double mission_time_s = 0.0;  // since the mission started (frozen when it ends)
  GoalOutcomes goals;
  std::int64_t plans = 0;       // plan results used
  std::int64_t looks_around = 0;  // turns on the spot before DONE_WITH_UNREACHABLE (MissionOptions::look_around)
  std::int64_t backs_out = 0;     // drives back the way it came before DONE_WITH_UNREACHABLE (back_out_m)
  // Ways in: goals taken with way_in_margin_m to a frontier whose approach
  // point was reached (Mission::through_frontier_).
  std::int64_t ways_in = 0;
  std::optional<PlanRequest> plan_request;  // run compute_plan() on it and call on_plan()
  PlanStats plan_stats;         // of the last plan
};

// What of a mission survives a restart of the explorer: where it started,
// how far it got, which goals it visited or gave up, and the operator's
// standing decision (waiting, paused, stopped, home, done). Not the goal in
// hand nor the path: a restarted mission selects again on the newest map.
struct MissionCheckpoint {
  Phase phase = Phase::kIdle;
  bool started = false;
  std::int64_t start_utime = -1;
  std::int64_t end_utime = -1;
  double travelled_m = 0.0;
  std::optional<Pose2> home;
  GoalOutcomes outcomes;
  std::int64_t plans = 0;
  std::vector<Point> visited;
  std::vector<Point> blacklist;
};
// A small text file, one fact a line ("polyexplore-mission 1" first).
std::string to_text(const MissionCheckpoint& checkpoint);
// nullopt (and why) for text that is not a checkpoint of this version.
std::optional<MissionCheckpoint> checkpoint_from_text(const std::string& text, std::string* why = nullptr);

class Mission {
 public:
  explicit Mission(MissionOptions options = {});

  // Inputs, with the time they arrived (us). A map replaces the previous one.
  // `scan_utime`: the newest scan in the map (MAP.scan_utime), -1 unknown.
  void on_map(TypedMultiPolygon map, std::int64_t utime, std::int64_t scan_utime = -1);
  void on_pose(const Pose2& pose, std::int64_t utime);
  // A laser scan arrived (only its time matters: the laser is alive).
  void on_scan(std::int64_t utime) { scan_utime_ = utime; }
  // An operator's command; idempotent (start while exploring does nothing).
  // Returns "" when applied, else why not (e.g. resume while not paused).
  std::string on_command(MissionCommand command, std::int64_t now_utime);
  // The answer to a plan_request; an answer to an older request is ignored.
  void on_plan(const PlanResult& result, std::int64_t now_utime);
  // The scan guard has held the robot still on its way to the goal (it
  // wanted to drive on; something the laser sees is in its way): the goal's
  // progress starts anew, measured from its follow plans on the next two
  // maps (which show what held the robot), and a plan is asked for now
  // (MissionOptions::max_guard_blocks_per_goal). Returns whether it did
  // (false: not moving to a goal, or the goal's holds are used up).
  bool on_guard_block(std::int64_t now_utime);

  // One control step at `now_utime`; call at the command rate. Never plans.
  MissionOutput step(std::int64_t now_utime);

  Phase phase() const { return phase_; }
  MissionCheckpoint checkpoint() const;
  // Takes up a checkpointed mission (call before the first step): exploring
  // phases resume by selecting anew; paused, stopped, home and the ended ones
  // stay as they were; homing goes on homing.
  void restore(const MissionCheckpoint& checkpoint);
  const std::vector<Point>& blacklist() const { return blacklist_; }
  // The newest planning map and robot pose the mission was given (null / none yet).
  const std::shared_ptr<const TypedMultiPolygon>& map() const { return map_; }
  const std::optional<Pose2>& pose() const { return pose_; }
  const std::vector<Point>& visited_goals() const { return visited_; }
  const GoalOutcomes& goal_outcomes() const { return outcomes_; }
  const MissionOptions& options() const { return options_; }

 private:
  enum class Purpose : std::int8_t { kSelect, kFollow, kHome };
  void request_plan(std::int64_t now_utime, Purpose purpose, bool tight);
  bool plan_due(std::int64_t now_utime) const;
  void on_select_plan(const Plan& plan, bool tight, std::int64_t now_utime);
  void on_follow_plan(const Plan& plan, std::int64_t now_utime);
  void on_home_plan(const Plan& plan, bool tight);
  void select(const Plan& plan, std::int64_t now_utime);
  // Sets `goal` (a candidate of `plan`) as the goal to drive to: MOVING.
  void start_goal(const GoalCandidate& goal, const Plan& plan, std::int64_t now_utime);
  // Plans with less than the clearance margin are allowed (the tight
  // fallback, a way in) and would differ from the plan with it.
  bool may_plan_tight() const { return options_.tight_fallback && options_.planner.cspace.clearance_margin_m > 0.0; }
  double way_in_margin_m() const {
    return std::min(options_.way_in_margin_m, options_.planner.cspace.clearance_margin_m);
  }
  // Why a goal is given up; give_up_goal counts it in GoalOutcomes.
  // kNoProgress (the robot could not get closer: stuck) and kOverdue (never
  // reached) count toward FAILED; kBlocked (a newer map has no path to it)
  // is the map changing, not the robot failing.
  enum class GiveUp { kBlocked, kNoProgress, kOverdue };
  void give_up_goal(GiveUp kind, const std::string& why);
  // What the last plan said of the goal (its frontier gone, no path to it)
  // is kept from acting on until a plan on a newer map says it too: true
  // while the plan is on the map `noted_map_utime` holds (noted now if -1).
  bool awaits_a_newer_map(std::int64_t& noted_map_utime) const;
  void count_plan_failure(const Plan& plan);
  // When a drive along a path of this length is over, however it seems to
  // progress: the progress timeout plus four times the path at full speed.
  std::int64_t deadline_for(double path_length_m, std::int64_t now_utime) const;
  void enter(Phase phase, std::string status);
  void finish(Phase phase, std::string status, std::int64_t now_utime);
  void list_frontiers(const Plan& plan);
  MissionOutput output() const;

  MissionOptions options_;
  PathFollower follower_;
  Phase phase_ = Phase::kIdle;
  Phase paused_from_ = Phase::kIdle;  // the phase a pause interrupted
  std::string status_ = "waiting for a map and a pose";
  bool degraded_ = false;
  bool started_ = false;
  std::int64_t start_utime_ = -1;
  std::int64_t end_utime_ = -1;  // the mission ended (finished, home, stopped)
  std::int64_t now_utime_ = 0;
  std::optional<Pose2> home_;    // the pose at the start of the mission

  std::shared_ptr<const TypedMultiPolygon> map_;
  std::int64_t map_utime_ = 0;
  double explored_area_m2_ = 0.0;
  std::optional<Pose2> pose_;
  std::int64_t pose_utime_ = 0;
  std::int64_t scan_utime_ = -1;  // the last scan's arrival (-1: none yet)
  double travelled_m_ = 0.0;

  std::int64_t last_step_utime_ = -1;
  // The plan asked for: its id, when, for what; 0 = none outstanding.
  std::uint64_t next_request_id_ = 1;
  std::uint64_t outstanding_id_ = 0;
  Purpose outstanding_purpose_ = Purpose::kSelect;
  bool outstanding_tight_ = false;
  std::int64_t outstanding_utime_ = 0;
  std::optional<PlanRequest> pending_request_;  // made, not yet handed out
  bool want_tight_ = false;                     // the next select plan goes without the margin
  bool home_tight_ = false;                     // the way home is planned without the margin (and along the trail)
  bool given_up_retried_ = false;               // this leg's goals given up had their second try
  // The look around before DONE_WITH_UNREACHABLE (MissionOptions::look_around).
  bool looking_around_ = false;
  double look_turned_rad_ = 0.0;
  double look_last_theta_ = 0.0;
  std::int64_t look_until_utime_ = 0;
  std::optional<Point> looked_around_at_;
  std::int64_t looks_around_ = 0;
  // The way back before DONE_WITH_UNREACHABLE (MissionOptions::back_out_m).
  std::vector<Point> trail_;  // where the robot has been, oldest first (a SLAM jump starts it anew)
  bool backing_out_ = false;
  bool backed_out_ = false;   // since the last goal
  // Where the last way back began: not again within kBackOutAgainM of it
  // (intel, tour: backed out, took a goal beside the nook without the
  // margin, was shut in again, twelve times over).
  std::optional<Point> backed_out_from_;
  // A way back that has not got to its end by then is over (the robot held
  // by something the mission does not see): as long as a goal of its length.
  std::int64_t back_out_deadline_utime_ = 0;
  static constexpr double kBackOutAgainM = 2.0;
  std::int64_t backs_out_ = 0;
  std::int64_t ways_in_ = 0;
  std::int64_t last_request_utime_ = -1;
  std::int64_t last_request_map_utime_ = -1;
  std::int64_t select_after_map_utime_ = -1;  // SELECTING waits for a map newer than this
  std::int64_t map_scan_utime_ = -1;          // the newest scan in the map (-1: not known)
  std::int64_t reached_utime_ = -1;           // the last goal was reached then ...
  std::int64_t scan_wait_until_utime_ = -1;   // ... and a map with a scan from then on is awaited until this
  std::int64_t last_empty_map_utime_ = -1;
  // The map on which the goal's frontier dropped out while no other goal was
  // reachable (-1: it has not): the goal is kept until a newer map confirms.
  std::int64_t goal_missing_map_utime_ = -1;
  // The map on which the goal followed first had no path (-1: it has one):
  // given up only when a newer map confirms.
  std::int64_t goal_blocked_map_utime_ = -1;
  int empty_plans_ = 0;
  int goal_failures_ = 0;
  int plan_failures_ = 0;
  std::int64_t plans_ = 0;

  std::optional<Point> goal_;
  Point goal_frontier_;      // the frontier point the goal is for
  bool goal_tight_ = false;  // the goal was planned without the clearance margin
  bool goal_approach_ = false;  // the goal is an approach point (GoalCandidate::approach)
  bool goal_way_in_ = false;    // the goal is a way in (through_frontier_), followed with way_in_margin_m()
  // An approach point was reached: the next select plan keeps only
  // way_in_margin_m and takes a way to this frontier's own place, if it has one.
  std::optional<Point> through_frontier_;
  double best_remaining_m_ = 0.0;
  int goal_guard_blocks_ = 0;        // on_guard_block()s of the goal in hand
  // After a guard block, the follow plans on the next kBaselineMaps maps
  // newer than the one of the block set the progress baseline (the map
  // that shows what held the robot comes a second or two after the hold).
  int baseline_maps_left_ = 0;
  std::int64_t baseline_map_utime_ = -1;  // the map the last baseline was set on
  static constexpr int kBaselineMaps = 2;
  Point progress_goal_;  // where the goal's frontier point was at the last progress
  std::int64_t progress_utime_ = 0;
  std::int64_t goal_deadline_utime_ = 0;  // given up (no progress) after this, whatever the progress
  // Where the robot was when it took the goal, and the farthest it has got
  // from there since: a robot that never got kStuckWithinM away is stuck.
  Point goal_taken_at_;
  double goal_moved_m_ = 0.0;
  static constexpr double kStuckWithinM = 1.0;
  std::int64_t pause_utime_ = 0;
  int goal_candidates_ = 0;
  std::vector<FrontierLeft> frontiers_;
  PlanStats plan_stats_;
  std::vector<Point> blacklist_;  // goals given up and goals reached
  std::vector<Point> visited_;
  // Where goals were seen (GoalOutcomes::came_back). Not checkpointed: a
  // restarted mission learns them again, at one more trip each.
  std::vector<Point> seen_at_;
  GoalOutcomes outcomes_;
};

// step(), then, while it asks for a plan, compute_plan() + on_plan() + step()
// again at the same time: the synchronous mission for tests and offline tools.
// `plan` runs a request (default compute_plan; a caller may wrap it, e.g. to time it).
MissionOutput step_with_inline_planning(
    Mission& mission, std::int64_t now_utime,
    const std::function<PlanResult(const PlanRequest&)>& plan = [](const PlanRequest& r) { return compute_plan(r); });

}  // namespace pex::planning
