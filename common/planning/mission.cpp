#include "planning/mission.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

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
  }
  return "?";
}

Mission::Mission(MissionOptions options) : options_(std::move(options)), follower_(options_.follower) {}

void Mission::on_map(TypedMultiPolygon map, std::int64_t utime) {
  explored_area_m2_ = mapping::area(map);
  map_ = std::move(map);
  map_utime_ = utime;
}

void Mission::on_pose(const Pose2& pose, std::int64_t utime) {
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.theta)) return;
  if (pose_) {
    const double step = std::hypot(pose.x - pose_->x, pose.y - pose_->y);
    if (step <= options_.max_travel_step_m) travelled_m_ += step;
  }
  pose_ = pose;
  pose_utime_ = utime;
}

void Mission::enter(Phase phase, std::string status) {
  phase_ = phase;
  status_ = std::move(status);
}

MissionOutput Mission::output(bool planned) const {
  MissionOutput out;
  out.phase = phase_;
  out.status = status_;
  out.degraded = degraded_;
  if (phase_ == Phase::kMoving && goal_) {
    out.goal = goal_;
    out.path = follower_.path();
  }
  out.goal_candidates = goal_candidates_;
  out.explored_area_m2 = explored_area_m2_;
  out.distance_travelled_m = travelled_m_;
  out.planned = planned;
  out.plan_stats = plan_stats_;
  return out;
}

Plan Mission::run_planner(std::int64_t now_utime, bool tight) {
  PlannerOptions planner = options_.planner;
  if (tight) planner.cspace.clearance_margin_m = 0.0;
  Plan plan = plan_exploration(*map_, *pose_, blacklist_, planner);
  last_plan_utime_ = now_utime;
  last_plan_map_utime_ = map_utime_;
  plan_stats_ = plan.stats;
  goal_candidates_ = static_cast<int>(plan.candidates.size());
  if (plan.ok) {
    plan_failures_ = 0;
  } else if (++plan_failures_ >= options_.max_consecutive_failures) {
    follower_.clear();
    goal_.reset();
    enter(Phase::kFailed, "planning failed " + std::to_string(plan_failures_) + " times in a row: " + plan.error);
  }
  return plan;
}

void Mission::plan_and_select(std::int64_t now_utime) {
  const Plan plan = run_planner(now_utime, false);
  if (phase_ == Phase::kFailed) return;
  bool blocked = plan.stats.candidates_not_in_cspace > 0;
  for (const auto& c : plan.candidates) blocked = blocked || (!c.blacklisted && !c.reachable);
  if (plan.ok && !plan.best_candidate() && blocked && options_.tight_fallback &&
      options_.planner.cspace.clearance_margin_m > 0.0) {
    const Plan tight = run_planner(now_utime, true);
    if (phase_ == Phase::kFailed) return;
    if (tight.ok && tight.best_candidate()) {
      select(tight, now_utime);
      goal_tight_ = true;
      status_ += " (without clearance margin)";
      return;
    }
  }
  select(plan, now_utime);
}

void Mission::select(const Plan& plan, std::int64_t now_utime) {
  goal_tight_ = false;
  if (!plan.ok) {
    if (phase_ != Phase::kFailed) status_ = "planning failed: " + plan.error;
    return;
  }
  const GoalCandidate* best = plan.best_candidate();
  if (!best) {
    follower_.clear();
    goal_.reset();
    phase_ = Phase::kSelecting;
    if (map_utime_ != last_empty_map_utime_) {
      ++empty_plans_;
      last_empty_map_utime_ = map_utime_;
    }
    int blacklisted = 0, unreachable = 0;
    for (const auto& c : plan.candidates) {
      if (c.blacklisted) ++blacklisted;
      else if (!c.reachable) ++unreachable;
    }
    std::string why;
    if (plan.candidates.empty() && plan.stats.candidates_not_in_cspace == 0) {
      why = "no frontier left";
    } else {
      why = std::to_string(plan.candidates.size() + static_cast<std::size_t>(plan.stats.candidates_not_in_cspace)) +
            " frontier goals left, none reachable (" + std::to_string(blacklisted) + " given up or visited, " +
            std::to_string(unreachable) + " without a path, " +
            std::to_string(plan.stats.candidates_not_in_cspace) + " too narrow for the robot)";
    }
    if (empty_plans_ >= options_.done_confirmations) {
      enter(Phase::kDone, "exploration done: " + why);
    } else {
      status_ = "no goal on this map (" + why + "); confirming on a newer map";
    }
    return;
  }
  empty_plans_ = 0;
  goal_ = best->position;
  progress_goal_ = best->position;
  best_remaining_m_ = best->path_length_m;
  progress_utime_ = now_utime;
  follower_.set_path(best->path);
  enter(Phase::kMoving, format("moving to goal (%.2f, %.2f), path %.1f m, %.0f candidates", best->position.x(),
                               best->position.y(), best->path_length_m, static_cast<double>(plan.candidates.size())));
}

void Mission::give_up_goal(const std::string& why) {
  if (goal_) blacklist_.push_back(*goal_);
  goal_.reset();
  follower_.clear();
  last_plan_utime_ = -1;  // plan again at the next step
  if (++goal_failures_ >= options_.max_consecutive_failures) {
    enter(Phase::kFailed, "gave up " + std::to_string(goal_failures_) + " goals in a row; the last: " + why);
  } else {
    enter(Phase::kSelecting, "gave up a goal: " + why);
  }
}

void Mission::replan_while_moving(std::int64_t now_utime) {
  const Plan plan = run_planner(now_utime, goal_tight_);
  if (!plan.ok) return;  // keep following the last path; run_planner counts failures
  int match = -1;
  double match_distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    const auto& c = plan.candidates[i];
    if (c.blacklisted) continue;
    const double d = distance(c.position, *goal_);
    if (d <= options_.goal_match_radius_m && d < match_distance) {
      match_distance = d;
      match = static_cast<int>(i);
    }
  }
  if (match < 0) {
    // The frontier behind the goal has been seen: a success, choose anew.
    goal_failures_ = 0;
    enter(Phase::kSelecting, "goal explored");
    if (goal_tight_) {
      last_plan_utime_ = -1;  // select on a plan with the full clearance first
    } else {
      select(plan, now_utime);
    }
    return;
  }
  const GoalCandidate& same = plan.candidates[static_cast<std::size_t>(match)];
  if (!same.reachable) {
    give_up_goal("no path to it any more");
    return;
  }
  const GoalCandidate* best = plan.best_candidate();
  if (!goal_tight_ && best && best != &same && best->cost < same.cost - options_.switch_margin_m) {
    select(plan, now_utime);
    return;
  }
  goal_ = same.position;
  follower_.set_path(same.path);
  // Progress: the path got shorter, or the goal moved on with its frontier
  // (a corridor's end recedes as the robot drives down it).
  if (same.path_length_m < best_remaining_m_ - options_.progress_min_m ||
      distance(same.position, progress_goal_) >= options_.progress_min_m) {
    best_remaining_m_ = same.path_length_m;
    progress_goal_ = same.position;
    progress_utime_ = now_utime;
  }
}

MissionOutput Mission::step(std::int64_t now_utime) {
  const double dt_s = last_step_utime_ < 0 ? 0.0 : static_cast<double>(now_utime - last_step_utime_) * 1e-6;
  last_step_utime_ = now_utime;

  if (phase_ == Phase::kDone || phase_ == Phase::kFailed) {
    follower_.stop();
    return output(false);
  }
  if (!map_ || !pose_) {
    follower_.stop();
    phase_ = Phase::kIdle;
    status_ = !map_ && !pose_ ? "waiting for a map and a pose" : !map_ ? "waiting for a map" : "waiting for a pose";
    return output(false);
  }

  const std::int64_t pose_age = now_utime - pose_utime_;
  const std::int64_t map_age = now_utime - map_utime_;
  if (pose_age > options_.pose_timeout_us || map_age > options_.map_timeout_us) {
    degraded_ = true;
    follower_.stop();
    MissionOutput out = output(false);
    out.degraded_reason = pose_age > options_.pose_timeout_us ? "pose is stale" : "map is stale";
    out.status = pose_age > options_.pose_timeout_us
                     ? format("stopped: pose is stale (%.0f ms old)", static_cast<double>(pose_age) * 1e-3)
                     : format("stopped: map is stale (%.0f ms old)", static_cast<double>(map_age) * 1e-3);
    return out;
  }
  if (degraded_) {
    degraded_ = false;
    progress_utime_ = now_utime;  // the stop was not the goal's fault
  }

  if (phase_ == Phase::kIdle) enter(Phase::kSelecting, "selecting the first goal");

  bool planned = false;
  if (phase_ == Phase::kSelecting) {
    if (map_utime_ <= select_after_map_utime_) {
      follower_.stop();
      status_ = "goal reached; waiting for the map to show it";
      return output(false);
    }
    if (map_utime_ != last_plan_map_utime_ || last_plan_utime_ < 0 ||
        now_utime - last_plan_utime_ >= options_.replan_period_us) {
      plan_and_select(now_utime);
      planned = true;
    }
  }

  if (phase_ == Phase::kMoving) {
    const Point here(pose_->x, pose_->y);
    if (distance(here, *goal_) <= options_.follower.goal_tolerance_m) {
      // Reached. The goal is not offered again: a frontier the laser cannot
      // clear from there would otherwise pull the robot back for ever.
      visited_.push_back(*goal_);
      blacklist_.push_back(*goal_);
      goal_failures_ = 0;
      goal_.reset();
      follower_.clear();
      select_after_map_utime_ = map_utime_;
      enter(Phase::kSelecting, format("goal (%.2f, %.2f) reached", visited_.back().x(), visited_.back().y()));
      return output(planned);
    }
    if (!planned && now_utime - last_plan_utime_ >= options_.replan_period_us) {
      replan_while_moving(now_utime);
      planned = true;
    }
    if (phase_ == Phase::kMoving && now_utime - progress_utime_ > options_.progress_timeout_us)
      give_up_goal(format("no progress for %.0f s", static_cast<double>(options_.progress_timeout_us) * 1e-6));
  }

  MissionOutput out = output(planned);
  if (phase_ == Phase::kMoving) {
    out.command = follower_.update(*pose_, dt_s);
  } else {
    follower_.stop();
  }
  return out;
}

}  // namespace pex::planning
