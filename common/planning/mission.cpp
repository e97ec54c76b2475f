#include "planning/mission.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <limits>
#include <numbers>
#include <utility>

#include "planning/driven_trail.hpp"
#include "planning/keep_out.hpp"
#include "planning/live_view.hpp"

namespace pex::planning {

namespace {

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
  return buf;
}

}  // namespace

const char* to_string(Phase phase) {
  switch (phase) {
    case Phase::kIdle: return "IDLE";
    case Phase::kSelecting: return "SELECTING";
    case Phase::kMoving: return "MOVING";
    case Phase::kDone: return "DONE";
    case Phase::kFailed: return "FAILED";
    case Phase::kDoneWithUnreachable: return "DONE_WITH_UNREACHABLE";
    case Phase::kWaitingStart: return "WAITING_START";
    case Phase::kPaused: return "PAUSED";
    case Phase::kHoming: return "HOMING";
    case Phase::kHome: return "HOME";
    case Phase::kStopped: return "STOPPED";
  }
  return "?";
}

bool is_finished(Phase phase) {
  return phase == Phase::kDone || phase == Phase::kDoneWithUnreachable || phase == Phase::kFailed;
}

const char* to_string(MissionCommand command) {
  switch (command) {
    case MissionCommand::kStart: return "start";
    case MissionCommand::kPause: return "pause";
    case MissionCommand::kResume: return "resume";
    case MissionCommand::kHome: return "home";
    case MissionCommand::kStop: return "stop";
  }
  return "?";
}

PlanKind plan_kind(const PlanRequest& request) {
  if (request.home) return PlanKind::kHome;
  if (request.tight) return PlanKind::kTight;
  return request.focus ? PlanKind::kFollow : PlanKind::kSelect;
}

const char* to_string(PlanKind kind) {
  switch (kind) {
    case PlanKind::kSelect: return "select";
    case PlanKind::kFollow: return "follow";
    case PlanKind::kTight: return "tight";
    case PlanKind::kHome: return "home";
  }
  return "?";
}

bool gives_a_way(const Plan& plan, const GoalFocus* focus) {
  if (!focus) return plan.best_candidate() != nullptr;
  return std::any_of(plan.candidates.begin(), plan.candidates.end(),
                     [&](const GoalCandidate& c) { return c.reachable && focus->matches(c); });
}

namespace {

// compute_plan with keep_out_areas for the request's keep_out.
PlanResult plan_keeping_out(const PlanRequest& request, const std::shared_ptr<const TypedMultiPolygon>& keep_out_areas,
                            PlanCache* cache) {
  PlanResult result;
  result.id = request.id;
  if (!request.map) {
    result.plan.error = "no map";
    return result;
  }
  // What the operator keeps the robot out of is a wall for every plan, also
  // where the newest scan sees free space (glass seen through). The map
  // without it is kept per map (the cache); the live view, a few metres
  // across, has it taken out on its own before it is united in: (M - K) u
  // (L - K) is (M u L) - K without a second pass over the whole map.
  const bool keep_out = keep_out_areas && !keep_out_areas->empty();
  mapping::TypedOpResult uncached;
  const mapping::TypedOpResult* kept = nullptr;
  if (keep_out) {
    if (cache) {
      kept = &cache->keep_out.without_keep_out(request.map, keep_out_areas);
    } else {
      uncached = without_keep_out(*request.map, *keep_out_areas);
      kept = &uncached;
    }
    if (!kept->ok) {
      // Never the map without them: a plan must not cross a line drawn at a stairwell.
      result.keep_out_failed = true;
      result.plan.error = "the keep-out could not be taken out of the map: " + kept->error;
      return result;
    }
  }
  const TypedMultiPolygon& map = keep_out ? kept->polygons : *request.map;
  // The newest scan opens where the robot may drive; the frontiers stay the map's.
  bool live = request.live_view && !request.live_view->empty();
  TypedMultiPolygon view;
  if (live && keep_out) {
    // Failed: the plan is the map's own, which has the keep-out.
    auto cut = without_keep_out(*request.live_view, *keep_out_areas);
    live = cut.ok && !cut.polygons.empty();
    if (live) view = std::move(cut.polygons);
  }
  // A tight plan also goes where the robot has driven.
  DrivenWay way;
  if (request.tight && request.trail) way = {*request.trail, request.options.trail_corridor_m};
  const DrivenWay* driven = way.points.empty() ? nullptr : &way;
  const GoalFocus* focus = request.focus ? &*request.focus : nullptr;
  auto plan_on = [&](const TypedMultiPolygon* opened) {
    return request.home ? plan_path_to(opened ? *opened : map, request.pose, *request.home, request.options, cache,
                                       driven)
                        : plan_exploration(map, request.pose, request.blacklist, request.options, opened, focus,
                                           cache, driven);
  };
  if (!live || request.live_view_when_stuck_only) {
    result.plan = plan_on(nullptr);
    if (!live || gives_a_way(result.plan, focus)) return result;
    result.live_view_used = true;  // stuck on the map alone: again, with the view
  }
  const TypedMultiPolygon opened = with_live_view(map, keep_out ? view : *request.live_view);
  result.plan = plan_on(&opened);
  return result;
}

}  // namespace

PlanResult compute_plan(const PlanRequest& request, PlanCache* cache) {
  PlanResult result = plan_keeping_out(request, request.keep_out, cache);
  if (!request.has_guard_marks) return result;
  // Any goal at all, not the one followed: the goal behind a pane the marks
  // shut is given up (no path) and another taken; only marks that shut the
  // robot in are dropped.
  if (!result.keep_out_failed && gives_a_way(result.plan, nullptr)) return result;
  result = plan_keeping_out(request, request.keep_out_without_marks, cache);
  result.guard_marks_dropped = true;
  return result;
}

std::string to_text(const MissionCheckpoint& c) {
  std::string t = "polyexplore-mission 1\n";
  char line[160];
  auto add = [&](const char* fmt, auto... args) {
    std::snprintf(line, sizeof line, fmt, args...);
    t += line;
  };
  add("phase %d\n", static_cast<int>(c.phase));
  add("started %d\n", c.started ? 1 : 0);
  add("start_utime %lld\n", static_cast<long long>(c.start_utime));
  add("end_utime %lld\n", static_cast<long long>(c.end_utime));
  add("travelled_m %.17g\n", c.travelled_m);
  if (c.home) add("home %.17g %.17g %.17g\n", c.home->x_m, c.home->y_m, c.home->theta_rad);
  add("outcomes %lld %lld %lld %lld %lld %lld\n", static_cast<long long>(c.outcomes.reached),
      static_cast<long long>(c.outcomes.seen), static_cast<long long>(c.outcomes.blocked),
      static_cast<long long>(c.outcomes.no_progress), static_cast<long long>(c.outcomes.overdue),
      static_cast<long long>(c.outcomes.came_back));
  add("plans %lld\n", static_cast<long long>(c.plans));
  for (const auto& p : c.visited) add("visited %.17g %.17g\n", p.x(), p.y());
  for (const auto& p : c.blacklist) add("blacklist %.17g %.17g\n", p.x(), p.y());
  t += "end\n";
  return t;
}

std::optional<MissionCheckpoint> checkpoint_from_text(const std::string& text, std::string* why) {
  auto fail = [&](const std::string& w) -> std::optional<MissionCheckpoint> {
    if (why) *why = w;
    return std::nullopt;
  };
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != "polyexplore-mission 1") return fail("not a mission checkpoint (version 1)");
  MissionCheckpoint c;
  bool ended = false;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream f(line);
    std::string key;
    f >> key;
    bool ok = true;
    if (key == "phase") {
      int p = -1;
      ok = static_cast<bool>(f >> p) && p >= 0 && p <= static_cast<int>(Phase::kStopped);
      c.phase = static_cast<Phase>(p);
    } else if (key == "started") {
      int b = 0;
      ok = static_cast<bool>(f >> b);
      c.started = b != 0;
    } else if (key == "start_utime") {
      ok = static_cast<bool>(f >> c.start_utime);
    } else if (key == "end_utime") {
      ok = static_cast<bool>(f >> c.end_utime);
    } else if (key == "travelled_m") {
      ok = static_cast<bool>(f >> c.travelled_m) && std::isfinite(c.travelled_m) && c.travelled_m >= 0.0;
    } else if (key == "home") {
      Pose2 h;
      ok = static_cast<bool>(f >> h.x_m >> h.y_m >> h.theta_rad) && std::isfinite(h.x_m) && std::isfinite(h.y_m) &&
           std::isfinite(h.theta_rad);
      c.home = h;
    } else if (key == "outcomes") {
      ok = static_cast<bool>(f >> c.outcomes.reached >> c.outcomes.seen >> c.outcomes.blocked >> c.outcomes.no_progress);
      // The fifth, overdue, and the sixth, came_back, are newer: a checkpoint
      // written before them has four or five.
      if (ok && !(f >> std::ws).eof()) ok = static_cast<bool>(f >> c.outcomes.overdue);
      if (ok && !(f >> std::ws).eof()) ok = static_cast<bool>(f >> c.outcomes.came_back);
    } else if (key == "plans") {
      ok = static_cast<bool>(f >> c.plans);
    } else if (key == "visited" || key == "blacklist") {
      double x = 0, y = 0;
      ok = static_cast<bool>(f >> x >> y) && std::isfinite(x) && std::isfinite(y);
      (key == "visited" ? c.visited : c.blacklist).emplace_back(x, y);
    } else if (key == "end") {
      ended = true;
      break;
    } else {
      return fail("line " + std::to_string(number) + ": unknown key '" + key + "'");
    }
    if (!ok) return fail("line " + std::to_string(number) + ": bad value for '" + key + "'");
  }
  // A file cut short (power lost while writing) lacks its "end" line.
  if (!ended) return fail("no 'end' line: the checkpoint is incomplete");
  return c;
}

MissionCheckpoint Mission::checkpoint() const {
  MissionCheckpoint c;
  c.phase = phase_;
  c.started = started_;
  c.start_utime = start_utime_;
  c.end_utime = end_utime_;
  c.travelled_m = travelled_m_;
  c.home = home_;
  c.outcomes = outcomes_;
  c.plans = plans_;
  c.visited = visited_;
  c.blacklist = blacklist_;
  return c;
}

void Mission::restore(const MissionCheckpoint& c) {
  started_ = c.started;
  start_utime_ = c.start_utime;
  end_utime_ = c.end_utime;
  travelled_m_ = c.travelled_m;
  home_ = c.home;
  outcomes_ = c.outcomes;
  plans_ = c.plans;
  visited_ = c.visited;
  blacklist_ = c.blacklist;
  switch (c.phase) {
    case Phase::kIdle:
    case Phase::kSelecting:
    case Phase::kMoving:
      enter(Phase::kIdle, "restored: exploring on");
      break;
    case Phase::kPaused:
      paused_from_ = Phase::kSelecting;  // the goal in hand is not kept: select anew on resume
      enter(Phase::kPaused, "restored: paused by command");
      break;
    case Phase::kHoming:
      if (!home_) {
        enter(Phase::kIdle, "restored: exploring on (no home pose to go to)");
        break;
      }
      enter(Phase::kHoming, "restored: going home");
      home_tight_ = false;
      last_request_utime_ = -1;
      break;
    default:
      enter(c.phase, std::string("restored: ") + to_string(c.phase));
      break;
  }
}

Mission::Mission(MissionOptions options) : options_(std::move(options)), follower_(options_.follower) {
  if (!options_.autostart) {
    phase_ = Phase::kWaitingStart;
    status_ = "waiting for a start command";
  }
}

void Mission::on_map(TypedMultiPolygon map, std::int64_t utime, std::int64_t scan_utime) {
  map_scan_utime_ = scan_utime;
  explored_area_m2_ = mapping::area(map);
  map_ = std::make_shared<const TypedMultiPolygon>(std::move(map));
  map_utime_ = utime;
}

void Mission::on_pose(const Pose2& pose, std::int64_t utime) {
  if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad)) return;
  if (pose_ && phase_ != Phase::kWaitingStart) {  // a robot pushed before the start is not the mission's travel
    const double step = std::hypot(pose.x_m - pose_->x_m, pose.y_m - pose_->y_m);
    if (step <= options_.max_travel_step_m) travelled_m_ += step;
    if (step > options_.max_travel_step_m) {  // the way before the jump is elsewhere in this frame
      trail_.clear();
      goal_taken_at_ = Point(pose.x_m, pose.y_m);  // and a jump is no move of the robot's
    }
  }
  if (started_ && (phase_ == Phase::kMoving || phase_ == Phase::kSelecting) && options_.back_out_m > 0.0) {
    constexpr double kTrailStepM = 0.1;
    const Point here(pose.x_m, pose.y_m);
    if (trail_.empty() || distance(trail_.back(), here) >= kTrailStepM) trail_.push_back(here);
    // Bounded: the oldest half goes when it holds twice what a way back needs.
    const auto cap = static_cast<std::size_t>(2.0 * options_.back_out_m / kTrailStepM) + 2;
    if (trail_.size() > 2 * cap) trail_.erase(trail_.begin(), trail_.end() - static_cast<std::ptrdiff_t>(cap));
  }
  if (phase_ == Phase::kMoving && goal_)
    goal_moved_m_ = std::max(goal_moved_m_, distance(Point(pose.x_m, pose.y_m), goal_taken_at_));
  pose_ = pose;
  pose_utime_ = utime;
}

std::int64_t Mission::deadline_for(double path_length_m, std::int64_t now_utime) const {
  return now_utime + options_.progress_timeout_us +
         static_cast<std::int64_t>(4e6 * path_length_m / options_.follower.max_speed_mps);
}

void Mission::enter(Phase phase, std::string status) {
  phase_ = phase;
  status_ = std::move(status);
}

void Mission::finish(Phase phase, std::string status, std::int64_t now_utime) {
  follower_.clear();
  backing_out_ = false;
  goal_.reset();
  outstanding_id_ = 0;
  pending_request_.reset();
  end_utime_ = now_utime;
  enter(phase, std::move(status));
}

std::string Mission::on_command(MissionCommand command, std::int64_t now_utime) {
  switch (command) {
    case MissionCommand::kStart:
      if (phase_ == Phase::kWaitingStart || phase_ == Phase::kStopped || phase_ == Phase::kHome ||
          is_finished(phase_)) {
        // A new leg of the same mission: what was visited stays visited, but
        // the frontiers given up get another chance and DONE is confirmed anew.
        blacklist_ = visited_;
        given_up_retried_ = false;
        goal_failures_ = plan_failures_ = empty_plans_ = 0;
        end_utime_ = -1;
        want_tight_ = false;
        through_frontier_.reset();
        trail_.clear();
        backing_out_ = backed_out_ = false;
        backed_out_from_.reset();
        enter(Phase::kIdle, "started");
        return {};
      }
      return phase_ == Phase::kPaused ? "paused: resume it" : "";
    case MissionCommand::kPause:
      if (phase_ == Phase::kPaused) return {};
      if (phase_ == Phase::kStopped || phase_ == Phase::kHome || phase_ == Phase::kWaitingStart || is_finished(phase_))
        return std::string("nothing to pause in phase ") + to_string(phase_);
      paused_from_ = phase_;
      pause_utime_ = now_utime;
      follower_.stop();
      enter(Phase::kPaused, "paused by command");
      return {};
    case MissionCommand::kResume:
      if (phase_ != Phase::kPaused) return phase_ == Phase::kWaitingStart ? "not started: send start" : "";
      enter(paused_from_, "resumed");
      goal_deadline_utime_ += now_utime - pause_utime_;  // the pause was not the goal's fault
      back_out_deadline_utime_ += now_utime - pause_utime_;
      progress_utime_ = now_utime;
      last_request_utime_ = -1;     // the world may have changed: plan again now
      return {};
    case MissionCommand::kHome:
      if (phase_ == Phase::kHoming || phase_ == Phase::kHome) return {};
      if (!home_) return "no start pose yet: the mission has not run";
      goal_.reset();
      follower_.clear();
      backing_out_ = false;
      outstanding_id_ = 0;
      end_utime_ = -1;
      enter(Phase::kHoming, format("going home to (%.2f, %.2f)", home_->x_m, home_->y_m));
      home_tight_ = false;
      last_request_utime_ = -1;
      return {};
    case MissionCommand::kStop:
      if (phase_ == Phase::kStopped) return {};
      finish(Phase::kStopped, "stopped by command", now_utime);
      return {};
  }
  return "unknown command";
}

MissionOutput Mission::output() const {
  MissionOutput out;
  out.phase = phase_;
  out.status = status_;
  out.degraded = degraded_;
  if ((phase_ == Phase::kMoving || phase_ == Phase::kHoming) && goal_) {
    out.goal = goal_;
    out.path = follower_.path();
  }
  out.goal_candidates = goal_candidates_;
  out.frontiers = frontiers_;
  out.explored_area_m2 = explored_area_m2_;
  out.distance_travelled_m = travelled_m_;
  if (start_utime_ >= 0)
    out.mission_time_s = static_cast<double>((end_utime_ >= 0 ? end_utime_ : now_utime_) - start_utime_) * 1e-6;
  out.goals = outcomes_;
  out.plans = plans_;
  out.looks_around = looks_around_;
  out.backs_out = backs_out_;
  out.ways_in = ways_in_;
  out.plan_stats = plan_stats_;
  return out;
}

void Mission::request_plan(std::int64_t now_utime, Purpose purpose, bool tight) {
  PlanRequest r;
  r.id = next_request_id_++;
  r.map = map_;
  r.map_utime = map_utime_;
  r.pose = *pose_;
  r.blacklist = blacklist_;
  r.options = options_.planner;
  r.tight = tight;
  if (tight) {
    // Without the margin; a way in keeps part of it (MissionOptions::way_in_margin_m).
    const bool way_in = (purpose == Purpose::kSelect && through_frontier_) || (purpose == Purpose::kFollow && goal_way_in_);
    r.options.cspace.clearance_margin_m = way_in ? way_in_margin_m() : 0.0;
  }
  if (purpose == Purpose::kHome) r.home = Point(home_->x_m, home_->y_m);
  if (purpose == Purpose::kFollow && goal_) r.focus = GoalFocus{*goal_, goal_frontier_, options_.goal_match_radius_m};
  if (purpose == Purpose::kSelect && tight && through_frontier_)
    r.focus = GoalFocus{*through_frontier_, *through_frontier_, options_.goal_match_radius_m};
  outstanding_id_ = r.id;
  outstanding_purpose_ = purpose;
  outstanding_tight_ = tight;
  outstanding_utime_ = now_utime;
  last_request_utime_ = now_utime;
  last_request_map_utime_ = map_utime_;
  pending_request_ = std::move(r);
}

bool Mission::plan_due(std::int64_t now_utime) const {
  if (outstanding_id_ != 0) return now_utime - outstanding_utime_ >= options_.plan_timeout_us;
  return last_request_utime_ < 0 || now_utime - last_request_utime_ >= options_.replan_period_us;
}

void Mission::count_plan_failure(const Plan& plan) {
  if (++plan_failures_ >= options_.max_consecutive_failures)
    finish(Phase::kFailed, "planning failed " + std::to_string(plan_failures_) + " times in a row: " + plan.error,
           now_utime_);
  else
    status_ = "planning failed: " + plan.error;
}

void Mission::on_plan(const PlanResult& result, std::int64_t now_utime) {
  if (result.id == 0 || result.id != outstanding_id_) return;  // an answer nobody waits for any more
  outstanding_id_ = 0;
  now_utime_ = std::max(now_utime_, now_utime);
  ++plans_;
  const Plan& plan = result.plan;
  plan_stats_ = plan.stats;
  if (!plan.ok) {
    if (outstanding_purpose_ == Purpose::kSelect && through_frontier_) {
      // A way in is tried on one plan only.
      through_frontier_.reset();
      want_tight_ = false;
    }
    if (plan.robot_outside_cspace && !outstanding_tight_ && may_plan_tight() &&
        (outstanding_purpose_ == Purpose::kSelect || outstanding_purpose_ == Purpose::kHome)) {
      // The robot stands where the margin leaves no room: a nook it reached
      // on a plan without the margin, or a pose SLAM put a little into a
      // wall's band. Plan again at once without the margin, as the tight
      // fallback does (intel: FAILED five plans later, in a nook whose
      // tight C-space had 41 candidates); the way home likewise.
      (outstanding_purpose_ == Purpose::kHome ? home_tight_ : want_tight_) = true;
      last_request_utime_ = -1;
      return;
    }
    if (backing_out_ && phase_ == Phase::kSelecting) {
      // On the way back through a door the map shows too narrow: no plan
      // starts there, and that is why the robot backs out.
      status_ = "backing out the way it came: " + plan.error;
      return;
    }
    count_plan_failure(plan);  // MOVING / HOMING keep following the last path meanwhile
    return;
  }
  plan_failures_ = 0;
  switch (outstanding_purpose_) {
    case Purpose::kSelect:
      if (phase_ == Phase::kSelecting) on_select_plan(plan, outstanding_tight_, now_utime);
      break;
    case Purpose::kFollow:
      if (phase_ == Phase::kMoving) on_follow_plan(plan, now_utime);
      break;
    case Purpose::kHome:
      if (phase_ == Phase::kHoming) on_home_plan(plan, outstanding_tight_);
      break;
  }
}

void Mission::list_frontiers(const Plan& plan) {
  goal_candidates_ = static_cast<int>(plan.candidates.size());
  frontiers_.clear();
  for (const auto& c : plan.candidates) {
    FrontierReason why = FrontierReason::kReachable;
    if (!c.reachable || (c.blacklisted && c.gap_mouth)) {
      // A gap's mouth blacklisted: the robot looked through the gap from
      // there (or could not get there) and has no way through it; whether
      // the robot's body would pass is not settled, so the frontier is left
      // without a path, not visited (docs/exploration.md, "A gap about the
      // robot's width").
      why = FrontierReason::kNoPath;
    } else if (c.blacklisted) {
      bool visited = false;
      for (const auto& v : visited_) visited = visited || distance(v, c.position) <= options_.planner.blacklist_radius_m;
      why = visited ? FrontierReason::kVisited : FrontierReason::kGivenUp;
    }
    frontiers_.push_back({c.position, why});
  }
  for (const auto& p : plan.narrow_frontier_points) frontiers_.push_back({p, FrontierReason::kTooNarrow});
  for (const auto& p : plan.out_of_view_frontier_points) frontiers_.push_back({p, FrontierReason::kOutOfView});
  for (const auto& p : plan.pocket_frontier_points) frontiers_.push_back({p, FrontierReason::kPocket});
  for (const auto& p : plan.enclosed_frontier_points) frontiers_.push_back({p, FrontierReason::kEnclosed});
  for (const auto& p : plan.behind_narrow_gap_points) frontiers_.push_back({p, FrontierReason::kBehindNarrowGap});
}

void Mission::on_select_plan(const Plan& plan, bool tight, std::int64_t now_utime) {
  list_frontiers(plan);
  if (through_frontier_) {
    const Point frontier = *through_frontier_;
    through_frontier_.reset();
    if (tight) {
      // The way to the frontier itself (not another approach point), if
      // the plan with the way in's margin has one (the request's focus had
      // the paths of the candidates near the frontier searched); otherwise
      // the usual plan with the full margin.
      const GoalFocus focus{frontier, frontier, options_.goal_match_radius_m};
      const GoalCandidate* way_in = nullptr;
      bool still_there = false;
      for (const auto& c : plan.candidates) {
        still_there = still_there || focus.distance_to(c) <= focus.radius_m;
        if (c.reachable && !c.approach && focus.matches(c) && !c.path.empty() &&
            (!way_in || c.path_length_m < way_in->path_length_m))
          way_in = &c;
      }
      want_tight_ = false;
      if (!way_in) {
        last_request_utime_ = -1;
        status_ = still_there ? "no way in to the frontier seen from its approach point"
                              : "the frontier seen from its approach point is cleared";
        return;
      }
      start_goal(*way_in, plan, now_utime);
      goal_tight_ = goal_way_in_ = true;
      ++ways_in_;
      status_ += format(" (a way in, clearance margin %.3f m: the frontier seen from its approach point)",
                        way_in_margin_m());
      return;
    }
  }
  if (!plan.best_candidate() && !tight && may_plan_tight()) {
    if (margin_may_block(plan)) {
      // Plan once more without the margin, right away, on the same map.
      want_tight_ = true;
      last_request_utime_ = -1;
      return;
    }
  }
  want_tight_ = false;
  select(plan, now_utime);
  if (tight && phase_ == Phase::kMoving) {
    goal_tight_ = true;
    status_ += " (without clearance margin)";
  }
}

void Mission::select(const Plan& plan, std::int64_t now_utime) {
  goal_tight_ = false;
  const GoalCandidate* best = plan.best_candidate();
  if (!best) {
    if (!looking_around_ && !backing_out_) follower_.clear();  // a turn or a way back goes on through its plans
    goal_.reset();
    phase_ = Phase::kSelecting;
    if (map_utime_ != last_empty_map_utime_) {
      ++empty_plans_;
      last_empty_map_utime_ = map_utime_;
    }
    int given_up = 0, visited = 0, no_path = 0;
    for (const auto& f : frontiers_) {
      given_up += f.reason == FrontierReason::kGivenUp;
      visited += f.reason == FrontierReason::kVisited;
      no_path += f.reason == FrontierReason::kNoPath;
    }
    const int narrow = plan.stats.candidates_not_in_cspace;
    const int out_of_view = plan.stats.candidates_out_of_view;
    const int pockets = plan.stats.candidates_in_pockets;
    const int enclosed = plan.stats.candidates_enclosed;
    const int behind_gaps = plan.stats.candidates_behind_narrow_gaps;
    // DONE when every frontier goal left has been visited (the robot stood
    // there facing it: the map keeps a frontier the laser could not clear),
    // is out of view (behind a wall, seen from no place the robot can
    // reach: a sliver of a misaligned scan beyond a wall, a room behind a
    // window), is a pocket (no robot reaches past it: the far side of a
    // gap narrower than the robot), is enclosed (the unknown behind it is
    // a small region the map closes in) or lies behind a gap narrower than
    // the robot (a room it sees into but cannot enter): driving cannot show
    // more of any of them that the robot could reach, or not enough to be
    // worth a trip. Any frontier it could not get to (no path, too narrow,
    // given up) makes it DONE_WITH_UNREACHABLE. Both list them.
    const bool nothing_left = no_path == 0 && given_up == 0 && narrow == 0;
    const std::string settled = std::to_string(visited) + " visited without clearing them, " +
                                std::to_string(out_of_view) + " behind walls, " + std::to_string(pockets) +
                                " in pockets narrower than the robot, " + std::to_string(enclosed) +
                                " enclosed in small unknown regions, " + std::to_string(behind_gaps) +
                                " behind gaps narrower than the robot)";
    std::string why;
    if (plan.candidates.empty() && narrow == 0 && out_of_view == 0 && pockets == 0 && enclosed == 0 &&
        behind_gaps == 0) {
      why = "no frontier left";
    } else if (nothing_left) {
      why = "every frontier left visited, out of view, in a pocket, enclosed or behind a gap narrower than the robot (";
      why += settled;
    } else {
      why = std::to_string(plan.candidates.size() +
                           static_cast<std::size_t>(narrow + out_of_view + pockets + enclosed + behind_gaps)) +
            " frontier goals left, none reachable (" + std::to_string(no_path) + " without a path, " +
            std::to_string(narrow) + " too narrow for the robot, " + std::to_string(given_up) + " given up, " +
            settled;
    }
    if (empty_plans_ >= options_.done_confirmations && given_up > 0 && !given_up_retried_) {
      // Before it calls the mission done, every goal given up gets one more
      // try, once a leg: a goal given up early (no progress while the map
      // was young and its path kept changing) is often plain to reach once
      // the rest is mapped (office, tour: one such goal was the mission's
      // only frontier left). Visited goals stay visited.
      given_up_retried_ = true;
      blacklist_ = visited_;
      empty_plans_ = 0;
      status_ = "trying the " + std::to_string(given_up) + " goals given up once more before finishing (" + why + ")";
      return;
    }
    const Point here(pose_->x_m, pose_->y_m);
    const std::string before_finishing = " before finishing (" + why + ")";
    if (empty_plans_ >= options_.done_confirmations && !nothing_left && options_.look_around && !looking_around_ &&
        (!looked_around_at_ || distance(here, *looked_around_at_) > 1.0)) {
      // Before it calls the rest unreachable: one turn on the spot, planning
      // on the newest scan as it goes round (MissionOptions::look_around).
      looking_around_ = true;
      look_turned_rad_ = 0.0;
      look_last_theta_ = pose_->theta_rad;
      look_until_utime_ = now_utime + options_.look_around_max_us;
      empty_plans_ = 0;
      ++looks_around_;
      status_ = "looking around" + before_finishing;
      return;
    }
    if (looking_around_) {
      status_ = "looking around" + before_finishing;
      return;
    }
    if (empty_plans_ >= options_.done_confirmations && !nothing_left && options_.back_out_m > 0.0 && !backing_out_ &&
        !backed_out_ && plan.stats.robot_in_a_lesser_piece &&
        (!backed_out_from_ || distance(here, *backed_out_from_) > kBackOutAgainM)) {
      // Then back the way it came, planning on the way (MissionOptions::back_out_m).
      auto way = way_back(trail_, options_.back_out_m);
      if (way.size() >= 2) {
        back_out_deadline_utime_ = deadline_for(polyline_length(way), now_utime);
        follower_.set_path(std::move(way));
        backing_out_ = true;
        backed_out_from_ = here;
        empty_plans_ = 0;
        ++backs_out_;
        status_ = "backing out the way it came" + before_finishing;
        return;
      }
    }
    if (backing_out_) {
      status_ = "backing out the way it came" + before_finishing;
      return;
    }
    if (empty_plans_ >= options_.done_confirmations) {
      finish(nothing_left ? Phase::kDone : Phase::kDoneWithUnreachable, "exploration done: " + why, now_utime);
    } else {
      status_ = "no goal on this map (" + why + "); confirming on a newer map";
    }
    return;
  }
  start_goal(*best, plan, now_utime);
}

void Mission::start_goal(const GoalCandidate& goal, const Plan& plan, std::int64_t now_utime) {
  empty_plans_ = 0;
  looking_around_ = false;
  backing_out_ = backed_out_ = false;
  goal_ = goal.position;
  goal_approach_ = goal.approach;
  goal_way_in_ = false;
  goal_missing_map_utime_ = -1;
  goal_blocked_map_utime_ = -1;
  goal_frontier_ = goal.frontier_point;
  progress_goal_ = goal.frontier_point;
  best_remaining_m_ = goal.path_length_m;
  progress_utime_ = now_utime;
  goal_guard_blocks_ = 0;
  baseline_maps_left_ = 0;
  goal_taken_at_ = Point(pose_->x_m, pose_->y_m);
  goal_moved_m_ = 0.0;
  // However the goal seems to progress, it gets at most this long (a goal
  // that keeps "moving on" without ever being reached is what makes a robot wander).
  goal_deadline_utime_ = deadline_for(goal.path_length_m, now_utime);
  follower_.set_path(goal.path);
  enter(Phase::kMoving, format("moving to goal (%.2f, %.2f), path %.1f m, %.0f candidates", goal.position.x(),
                               goal.position.y(), goal.path_length_m, static_cast<double>(plan.candidates.size())) +
                            (goal.gap_mouth ? ", to look through a gap about the robot's width" : ""));
}

void Mission::give_up_goal(GiveUp kind, const std::string& why) {
  switch (kind) {
    case GiveUp::kBlocked: ++outcomes_.blocked; break;
    case GiveUp::kNoProgress: ++outcomes_.no_progress; break;
    case GiveUp::kOverdue: ++outcomes_.overdue; break;
  }
  if (goal_) blacklist_.push_back(*goal_);
  goal_.reset();
  follower_.clear();
  last_request_utime_ = -1;  // plan again at the next step
  // A blocked goal leaves the count as it is: the end of a mission in clutter
  // gives up goals behind passages SLAM's corrections open and close, one
  // after another (intel, greedy: FAILED at coverage 0.993 after five), and
  // each is blacklisted, so they run out; a stuck robot still fails on the
  // goals it makes no progress to.
  // In the round that retries the goals given up, giving one up again is
  // what a goal the robot cannot get to ends in, not a robot failing: it is
  // blacklisted again, the round runs out and the mission ends
  // DONE_WITH_UNREACHABLE listing it (campus, docs/exploration.md "camp2":
  // in that round the robot drove 16 m to two such goals by turns, their
  // paths growing as it went, SLAM's pose 6 m off the truth, and it ended
  // FAILED at coverage 0.964). A robot that did not get kStuckWithinM from
  // where it took the goal still counts: it is stuck.
  const bool stuck = goal_moved_m_ < kStuckWithinM;
  const bool counts = kind != GiveUp::kBlocked && (!given_up_retried_ || stuck);
  if (counts && ++goal_failures_ >= options_.max_consecutive_failures) {
    finish(Phase::kFailed,
           "gave up " + std::to_string(goal_failures_) + " goals in a row unreached; the last: " + why,
           now_utime_);
  } else {
    enter(Phase::kSelecting, "gave up a goal: " + why);
  }
}

bool Mission::awaits_a_newer_map(std::int64_t& noted_map_utime) const {
  if (noted_map_utime < 0) noted_map_utime = last_request_map_utime_;
  return last_request_map_utime_ == noted_map_utime;
}

void Mission::on_follow_plan(const Plan& plan, std::int64_t now_utime) {
  list_frontiers(plan);
  // The same match the planner searched paths for (PlanRequest::focus).
  // The nearest reachable match: in clutter several candidates match one
  // goal (its frontier seen past a chair leg, a sliver beside it), and an
  // unreachable one nearer the goal does not block the goal while another
  // with a path still sees its frontier. Unreachable only if all are.
  // Nearest in both where to stand and what to look at: several frontiers
  // share one approach point (the place that sees them all), and taking
  // whichever came first swapped the goal's frontier from plan to plan, up
  // to metres away, so the robot at the goal turned to face each in turn
  // until the deadline gave the goal up (b34, fr079 greedy: the robot
  // 0.12 m from its goal, its heading swinging by over 100 degrees).
  const GoalFocus focus{*goal_, goal_frontier_, options_.goal_match_radius_m};
  int match = -1;
  double match_distance = std::numeric_limits<double>::infinity();
  bool match_reachable = false;
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    const auto& c = plan.candidates[i];
    if (!focus.matches(c)) continue;
    const double d = distance(c.position, focus.goal) + distance(c.frontier_point, focus.frontier);
    if ((c.reachable && !match_reachable) || (c.reachable == match_reachable && d < match_distance)) {
      match_distance = d;
      match = static_cast<int>(i);
      match_reachable = c.reachable;
    }
  }
  if (match < 0) {
    // Gone from this map: a frontier behind a passage that SLAM's
    // corrections open and close drops out of one map and comes back in the
    // next (intel, greedy: 400 s and 27 m of path to one goal that never
    // shrank, MOVING and "no goal on this map" by turns, each turn a stop;
    // with other goals in reach, a switch to one of them and back, 10-18 m
    // each way). The goal and its path are kept until a newer map confirms.
    if (awaits_a_newer_map(goal_missing_map_utime_)) {
      status_ = "goal's frontier not on this map: going on until a newer map confirms";
      return;
    }
  }
  goal_missing_map_utime_ = -1;
  if (match < 0) {
    // The frontier behind the goal has been seen: a success, choose anew;
    // unless a goal here was seen before and its frontier came back (b30,
    // intel greedy: one place chosen six times, 5-10 m each), which the
    // robot cannot clear by driving there: given up here (retried once
    // before the mission ends, as every goal given up).
    const Point at = *goal_;
    const bool seen_here_before = std::any_of(seen_at_.begin(), seen_at_.end(), [&](const Point& p) {
      return distance(p, at) <= options_.goal_match_radius_m;
    });
    goal_failures_ = 0;
    goal_.reset();
    follower_.clear();
    if (seen_here_before) {
      ++outcomes_.came_back;
      blacklist_.push_back(at);
      enter(Phase::kSelecting, "goal seen again where its frontier came back before: given up here");
    } else {
      ++outcomes_.seen;
      seen_at_.push_back(at);
      enter(Phase::kSelecting, "goal seen");
    }
    if (goal_tight_) {
      last_request_utime_ = -1;  // select on a plan with the full clearance first
    } else {
      select(plan, now_utime);
    }
    return;
  }
  const GoalCandidate& same = plan.candidates[static_cast<std::size_t>(match)];
  if (!same.reachable) {
    // Without a path on one plan: kept, on the path it had, until a newer
    // map confirms. Plans on one map differ in the robot's pose and the
    // live view's scan, and at a passage about the margin's width one of
    // them splits the C-space where the next joins it again (session 43, d1, intel:
    // the robot in a 0.14 m2 piece, the rest 0.52 m away, 40 ms before and
    // after a plan with the path; ten goals given up so in one run, each a
    // goal switch and, at the end, a trip back for the retry round).
    if (awaits_a_newer_map(goal_blocked_map_utime_)) {
      status_ = "no path to the goal on this map: going on until a newer map confirms";
      return;
    }
    give_up_goal(GiveUp::kBlocked, "no path to it any more");
    return;
  }
  goal_blocked_map_utime_ = -1;
  // Commitment: the goal is kept even when another candidate is now cheaper;
  // switching back and forth between goals is what makes a robot wander.
  goal_ = same.position;
  goal_approach_ = same.approach;
  goal_frontier_ = same.frontier_point;
  follower_.set_path(same.path);
  // After a guard block the path is measured from the plans on the next
  // maps on: it may go round what held the robot, longer than the one before.
  if (baseline_maps_left_ > 0 && last_request_map_utime_ > baseline_map_utime_) {
    --baseline_maps_left_;
    baseline_map_utime_ = last_request_map_utime_;
    best_remaining_m_ = same.path_length_m;
    progress_goal_ = same.frontier_point;
    progress_utime_ = now_utime;
    goal_deadline_utime_ = deadline_for(same.path_length_m, now_utime);
  }
  // Progress: the path got shorter, or the frontier moved on (a corridor's
  // end recedes as the robot drives down it). The goal point moving alone
  // is not progress: it may jump between a frontier's approach point and its
  // own C-space point from one map to the next.
  if (same.path_length_m < best_remaining_m_ - options_.progress_min_m ||
      distance(same.frontier_point, progress_goal_) >= options_.progress_min_m) {
    best_remaining_m_ = same.path_length_m;
    progress_goal_ = same.frontier_point;
    progress_utime_ = now_utime;
  }
}

bool Mission::on_guard_block(std::int64_t now_utime) {
  if (phase_ != Phase::kMoving || !goal_ || goal_guard_blocks_ >= options_.max_guard_blocks_per_goal) return false;
  ++goal_guard_blocks_;
  // The time the maps need to show what held the robot (SLAM's update of a
  // standing robot, the mapper's next MAP) is no want of progress either.
  progress_utime_ = now_utime;
  baseline_maps_left_ = kBaselineMaps;
  baseline_map_utime_ = map_utime_;
  if (outstanding_id_ == 0) last_request_utime_ = -1;  // a plan at the next step
  status_ = format("held by the scan guard (%.0f of %.0f for this goal): replanning round what holds it",
                   static_cast<double>(goal_guard_blocks_), static_cast<double>(options_.max_guard_blocks_per_goal));
  return true;
}

void Mission::on_home_plan(const Plan& plan, bool tight) {
  const GoalCandidate* home = plan.best_candidate();
  if (!home && !tight && may_plan_tight() && margin_may_block(plan)) {
    // The way the robot came is a way home, whatever a newer map makes of a
    // gap on it: plan again without the margin and along the trail
    // (PlanRequest::trail), and go on so until home.
    home_tight_ = true;
    last_request_utime_ = -1;
    status_ = "no path home with the clearance margin: planning without it, along the way the robot drove";
    return;
  }
  if (!home) {
    finish(Phase::kFailed, "cannot go home: no path to the start pose", now_utime_);
    return;
  }
  goal_ = home->position;
  follower_.set_path(home->path);
}

MissionOutput Mission::step(std::int64_t now_utime) {
  const double dt_s = last_step_utime_ < 0 ? 0.0 : static_cast<double>(now_utime - last_step_utime_) * 1e-6;
  last_step_utime_ = now_utime;
  now_utime_ = now_utime;
  pending_request_.reset();

  auto stopped = [&] {
    follower_.stop();
    return output();
  };
  if (is_finished(phase_) || phase_ == Phase::kWaitingStart || phase_ == Phase::kStopped ||
      phase_ == Phase::kHome || phase_ == Phase::kPaused)
    return stopped();
  if (!map_ || !pose_) {
    phase_ = Phase::kIdle;
    status_ = !map_ && !pose_ ? "waiting for a map and a pose" : !map_ ? "waiting for a map" : "waiting for a pose";
    return stopped();
  }

  const std::int64_t pose_age = now_utime - pose_utime_;
  const std::int64_t map_age = now_utime - map_utime_;
  const bool scans_stale = options_.scan_timeout_us > 0 &&
                           (scan_utime_ < 0 || now_utime - scan_utime_ > options_.scan_timeout_us);
  if (pose_age > options_.pose_timeout_us || map_age > options_.map_timeout_us || scans_stale) {
    degraded_ = true;
    MissionOutput out = stopped();
    if (pose_age > options_.pose_timeout_us) {
      out.degraded_reason = "pose is stale";
      out.status = format("stopped: pose is stale (%.0f ms old)", static_cast<double>(pose_age) * 1e-3);
    } else if (map_age > options_.map_timeout_us) {
      out.degraded_reason = "map is stale";
      out.status = format("stopped: map is stale (%.0f ms old)", static_cast<double>(map_age) * 1e-3);
    } else {
      out.degraded_reason = "no laser scans";
      out.status = scan_utime_ < 0 ? std::string("stopped: no laser scan yet")
                                   : format("stopped: no laser scan for %.0f ms (driving blind otherwise)",
                                            static_cast<double>(now_utime - scan_utime_) * 1e-3);
    }
    return out;
  }
  if (degraded_) {
    degraded_ = false;
    progress_utime_ = now_utime;  // the stop was not the goal's fault
  }

  if (phase_ == Phase::kIdle) {
    if (!started_) {
      started_ = true;
      start_utime_ = now_utime;
      home_ = pose_;
    }
    enter(Phase::kSelecting, "selecting the first goal");
  }

  if (phase_ == Phase::kSelecting) {
    // After a goal: a newer map, and one holding a scan taken there (the
    // look at the frontier), or a frontier the robot just saw counts as
    // "visited without clearing it". Bounded: a mapper that inserts only on
    // motion never sends one.
    const bool scan_missing = map_scan_utime_ >= 0 && map_scan_utime_ < reached_utime_ &&
                              now_utime < scan_wait_until_utime_;
    if (map_utime_ <= select_after_map_utime_ || scan_missing) {
      status_ = "goal reached; waiting for the map to show it";
      return stopped();
    }
    // A new map, the period, or the tight retry: ask (once) for a plan.
    const bool fresh_map = map_utime_ != last_request_map_utime_;
    if (outstanding_id_ == 0 ? (fresh_map || want_tight_ || plan_due(now_utime)) : plan_due(now_utime))
      request_plan(now_utime, Purpose::kSelect, want_tight_);
    if (looking_around_) {
      look_turned_rad_ += std::abs(geometry::wrap_angle(pose_->theta_rad - look_last_theta_));
      look_last_theta_ = pose_->theta_rad;
      if (look_turned_rad_ >= 2.0 * std::numbers::pi || now_utime >= look_until_utime_) {
        // Round once (or out of time): the plans made on the way decide.
        looking_around_ = false;
        looked_around_at_ = Point(pose_->x_m, pose_->y_m);
        status_ = "looked around; confirming on a newer map";
      } else {
        MissionOutput out = output();
        out.command = follower_.turn_to(*pose_, pose_->theta_rad + 1.0, dt_s);  // always 1 rad ahead: round and round
        out.plan_request = pending_request_;
        return out;
      }
    }
    if (backing_out_) {
      if (follower_.goal_reached() || now_utime > back_out_deadline_utime_) {
        // Back as far as it goes, or as far as it got in the time: the plans
        // made there decide (a way back never ends the mission by itself).
        status_ = follower_.goal_reached() ? "backed out; confirming on a newer map"
                                           : "the way back took too long; confirming on a newer map";
        backing_out_ = false;
        backed_out_ = true;
        follower_.clear();
      } else {
        MissionOutput out = output();
        out.command = follower_.update(*pose_, dt_s);
        out.plan_request = pending_request_;
        return out;
      }
    }
  }

  if (phase_ == Phase::kMoving) {
    const Point here(pose_->x_m, pose_->y_m);
    if (distance(here, *goal_) <= options_.follower.goal_tolerance_m) {
      // There: face the frontier first, or the laser may never have seen it
      // (a goal right behind the robot at the start is the common case).
      const double to_frontier = distance(here, goal_frontier_);
      const double bearing = std::atan2(goal_frontier_.y() - here.y(), goal_frontier_.x() - here.x());
      if (options_.look_tolerance_rad > 0.0 && to_frontier > 0.05 &&
          std::abs(geometry::wrap_angle(bearing - pose_->theta_rad)) > options_.look_tolerance_rad) {
        MissionOutput out = output();
        out.command = follower_.turn_to(*pose_, bearing, dt_s);
        out.status = status_;
        return out;
      }
      // Reached. The goal is not offered again: a frontier the laser cannot
      // clear from there would otherwise pull the robot back for ever.
      visited_.push_back(*goal_);
      blacklist_.push_back(*goal_);
      ++outcomes_.reached;
      if (goal_approach_ && !goal_tight_ && may_plan_tight()) {
        // An approach point: the robot sees the frontier from its own piece
        // of the C-space, the frontier's own place lies in another, and the
        // margin may be what cuts them apart (b41, an office floor: a 0.66 m
        // gap between a door's corner and a chair; the approach point reached,
        // the frontier still there, and the rest of the floor never entered,
        // although the plan without the margin went through; by the end of
        // the mission SLAM's corrections had closed it for both). Next: a
        // plan with less margin (way_in_margin_m), here and now, for that
        // frontier only.
        through_frontier_ = goal_frontier_;
        want_tight_ = true;
      }
      goal_failures_ = 0;
      goal_.reset();
      follower_.clear();
      outstanding_id_ = 0;  // a plan for the old goal is of no use
      select_after_map_utime_ = map_utime_;
      reached_utime_ = now_utime;
      scan_wait_until_utime_ = now_utime + 3 * options_.replan_period_us;
      enter(Phase::kSelecting, format("goal (%.2f, %.2f) reached", visited_.back().x(), visited_.back().y()));
      return stopped();
    }
    if (plan_due(now_utime)) request_plan(now_utime, Purpose::kFollow, goal_tight_);
    if (now_utime - progress_utime_ > options_.progress_timeout_us) {
      give_up_goal(GiveUp::kNoProgress,
                   format("no progress for %.0f s", static_cast<double>(options_.progress_timeout_us) * 1e-6));
    } else if (now_utime > goal_deadline_utime_) {
      give_up_goal(GiveUp::kOverdue, "not reached in four times its path's driving time");
    }
  }

  if (phase_ == Phase::kHoming) {
    const Point here(pose_->x_m, pose_->y_m);
    if (distance(here, Point(home_->x_m, home_->y_m)) <= options_.follower.goal_tolerance_m) {
      finish(Phase::kHome, format("home: back at (%.2f, %.2f)", home_->x_m, home_->y_m), now_utime);
      return stopped();
    }
    if (plan_due(now_utime)) request_plan(now_utime, Purpose::kHome, home_tight_);
  }

  MissionOutput out = output();
  if ((phase_ == Phase::kMoving || phase_ == Phase::kHoming) && goal_) {
    out.command = follower_.update(*pose_, dt_s);
  } else {
    follower_.stop();
  }
  out.plan_request = pending_request_;
  return out;
}

MissionOutput step_with_inline_planning(Mission& mission, std::int64_t now_utime,
                                        const std::function<PlanResult(const PlanRequest&)>& plan) {
  MissionOutput out = mission.step(now_utime);
  // Bounded: a select plan may ask for its tight retry, which may select.
  for (int round = 0; round < 4 && out.plan_request; ++round) {
    mission.on_plan(plan(*out.plan_request), now_utime);
    out = mission.step(now_utime);
  }
  return out;
}

}  // namespace pex::planning
