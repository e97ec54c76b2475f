#pragma once
// The maps an exploration mission plans on, without the daemons: a robot
// that follows each plan's path exactly in a simulator world (pex::sim's
// ray-cast LMS111 with its noise), a scan inserted into a PolygonMap every
// `scan_step_m` of the path and one at each goal facing its frontier, the
// planning map taken and planned on (greedy) every `replan_step_m` of travel
// and at each goal, as the explorer's replan period does. Poses are the
// truth (no SLAM), so the maps are those of a perfect localisation; the map
// grows, frontiers come and go, and the planner sees every map size of a
// mission. Deterministic: fixed seeds.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "mapping/known_walls.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"
#include "planning/exploration_planner.hpp"
#include "planning/path_follower.hpp"
#include "sim/sim.hpp"

namespace pex::bench {

struct MissionSnapshot {
  mapping::TypedMultiPolygon map;
  planning::Pose2 pose;
  std::vector<mapping::Point> blacklist;
};

struct MissionMaps {
  std::vector<MissionSnapshot> snapshots;  // in mission order
  int goals = 0;       // goals taken (reached, or seen on the way with replan_on_the_way)
  int goals_seen = 0;  // ... of which left on the way because their frontier was seen
  int backs_out = 0;   // ways back (MissionMapsOptions::back_out_m)
  int ways_in = 0;     // goals taken through a way in (emulate_mission's `way_in`)
  int guard_stops = 0;  // goals (counted in goals) given up on paths stopped short of a wall the map did not hold (MissionMapsOptions::robot_radius_m)
  int plans = 0;
  double travelled_m = 0.0;
  bool done = false;  // no reachable candidate left before max_goals
  mapping::TypedMultiPolygon free_space;  // the map's free space (MAP_FREE) when the mission ended
  std::string error;
};

struct MissionMapsOptions {
  int max_goals = 40;
  double scan_step_m = 0.25;    // the mapper inserts after 0.2 m; 0.25 keeps set-up time down
  double replan_step_m = 2.0;   // a snapshot every this much travel (0.4 m/s, 1 s replans: 0.4)
  double max_travel_m = 1e9;
  // As the explorer's mission does: plan again at every snapshot on the way,
  // and leave the goal for the new plan's best when no candidate of it lies
  // within goal_match_radius_m of the goal (its frontier has been seen).
  // Off: every goal is driven to its end (the planning benchmark's maps).
  bool replan_on_the_way = false;
  double goal_match_radius_m = 1.5;
  // The plans on the way carry the goal followed (MissionPlanner's focus),
  // as the explorer's follow plans do, and the goal is kept while a
  // candidate matches it (GoalFocus::matches). Off: they choose anew and the
  // goal is kept while a candidate lies within goal_match_radius_m of its
  // place. Off by default: the emulator has none of the mission's other
  // rules about a followed goal (a newer map to confirm it gone, a goal seen
  // again given up), and with this alone greedy drove 42 % more on one
  // office floor than without and than the daemons did (docs/exploration.md,
  // "The plans on the way carry the goal").
  bool carry_goal = false;
  // As the mission does before it ends with frontiers left it cannot reach
  // (MissionOptions::back_out_m): back the way the robot came, up to this
  // far, planning every replan_step_m on the way; once until the next goal.
  // 0: off (the planning benchmark's maps).
  double back_out_m = 0.0;
  // The robot's disk (m): a path that would bring it into contact with a
  // wall of the world is stopped short there, as the explorer's scan guard
  // stops the robot, and its goal given up (blacklisted). Without it the
  // emulated robot drove through a chair leg the map did not hold, and its
  // scans from within the laser's minimum range (no return, free for 4 m)
  // put free space through the wall behind (docs/exploration.md, walled
  // bays over four starts). 0: paths are followed whatever is in the way
  // (the planning benchmark's maps).
  double robot_radius_m = 0.0;
  // Snapshots are kept (the planning benchmark plans on them again); off for
  // long runs that only want the outcome.
  bool keep_snapshots = true;
  // The scans and the map as the mapper makes them (range_max_m is capped
  // at the laser's).
  mapping::ScanPolygonOptions scan;
  mapping::PolygonMapOptions map;
};

// The world file at `path`; nullopt and `error` when it cannot be read or parsed.
inline std::optional<sim::World> read_world(const std::string& path, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = "cannot read " + path;
    return std::nullopt;
  }
  std::stringstream text;
  text << in.rdbuf();
  auto parsed = sim::parse_world(text.str(), path);
  if (const auto* e = std::get_if<sim::WorldError>(&parsed)) {
    error = e->message;
    return std::nullopt;
  }
  return std::get<sim::World>(std::move(parsed));
}

// The planner the emulated robot follows. `focus` is the goal it is on its
// way to (nullptr when it chooses a new one), as the explorer's follow plans
// carry it (planning::GoalFocus): a followed goal's frontier stays a
// candidate where a new plan would leave it out (an enclosed frontier beyond
// enclosed_goal_range_m, a gap's mouth).
using MissionPlanner = std::function<planning::Plan(const mapping::TypedMultiPolygon&, const planning::Pose2&,
                                                    const std::vector<mapping::Point>&, const planning::GoalFocus*)>;

// `plan` is the planner the emulated robot follows (the goal order and so the
// maps depend on it: use one fixed planner for a benchmark's maps).
// `way_in`, when given, is that planner with the way in's clearance margin
// (MissionOptions::way_in_margin_m): when the robot has reached an approach
// point, it plans with it once more, the approach's frontier its focus, and
// takes the shortest path to the frontier's own place (a reachable candidate
// matching the focus that is no approach point itself) as its next goal,
// planning on the way with it too, as Mission::on_select_plan does. Without
// it, a frontier whose gap the full margin closes stays behind the approach
// point, already visited, and the mission ends there: an office floor's
// open plan behind a chair 0.66 m from the passage's corner, half the floor
// (docs/exploration.md, "When the look does not open it: the way in"). The
// emulator does not tell a goal of the tight fallback from one with the
// margin (the planner falls back inside): it looks for a way in after
// either, where the mission skips it after a tight one.
inline MissionMaps emulate_mission(const sim::World& world, const MissionMapsOptions& options,
                                   const MissionPlanner& plan, const MissionPlanner& way_in = {}) {
  MissionMaps out;
  const sim::RayCaster caster(world);
  sim::Laser laser(sim::LaserOptions{}, 11);
  mapping::ScanPolygonOptions scan_options = options.scan;
  scan_options.range_max_m = std::min(scan_options.range_max_m, laser.options().max_range_m);
  mapping::PolygonMap map(options.map);

  auto insert_at = [&](double x, double y, double theta) {
    const auto ranges = laser.scan(caster, sim::Pose2{x, y, theta});
    // As the mapper inserts it (beams without a return stopped at the map's walls).
    const auto scan = mapping::scan_to_polygon_in(map, ranges, laser.options().first_angle_rad(),
                                                  laser.options().step_deg * std::numbers::pi / 180.0,
                                                  geometry::Pose2{x, y, theta}, scan_options);
    if (scan.ok) map.insert(scan.polygon);
  };
  planning::Pose2 pose = world.start;
  insert_at(pose.x_m, pose.y_m, pose.theta_rad);
  std::vector<mapping::Point> trail{mapping::Point(pose.x_m, pose.y_m)};  // every scan's place
  bool backed_out = false;
  std::vector<mapping::Point> blacklist;
  MissionSnapshot latest;
  auto snapshot = [&]() -> const MissionSnapshot* {
    auto merged = map.planning_map();
    if (!merged.ok) return nullptr;
    latest = {std::move(merged.polygons), pose, blacklist};
    if (!options.keep_snapshots) return &latest;
    out.snapshots.push_back(latest);
    return &out.snapshots.back();
  };
  // The plan to follow next, when one made on the way already chose it.
  std::optional<planning::Plan> next_plan;
  // The frontier of the approach point just reached (a way in is looked for).
  std::optional<mapping::Point> through_frontier;
  double since_replan = 0.0;
  while (out.goals < options.max_goals && out.travelled_m < options.max_travel_m) {
    const MissionSnapshot* s = snapshot();
    if (!s) {
      out.error = "planning map failed";
      return out;
    }
    // The goal's plans on the way are made with the planner that found it.
    const MissionPlanner* goal_planner = &plan;
    if (through_frontier && !next_plan) {
      const planning::GoalFocus focus{*through_frontier, *through_frontier, options.goal_match_radius_m};
      planning::Plan p = way_in(s->map, s->pose, s->blacklist, &focus);
      ++out.plans;
      int shortest = -1;
      for (std::size_t i = 0; i < p.candidates.size(); ++i) {
        const auto& c = p.candidates[i];
        if (c.reachable && !c.approach && focus.matches(c) && !c.path.empty() &&
            (shortest < 0 || c.path_length_m < p.candidates[static_cast<std::size_t>(shortest)].path_length_m))
          shortest = static_cast<int>(i);
      }
      if (shortest >= 0) {
        p.best = shortest;
        next_plan = std::move(p);
        goal_planner = &way_in;
        ++out.ways_in;
      }
    }
    through_frontier.reset();
    const planning::Plan p = next_plan ? std::move(*next_plan) : plan(s->map, s->pose, s->blacklist, nullptr);
    if (!next_plan) ++out.plans;
    next_plan.reset();
    const planning::GoalCandidate* goal = p.best_candidate();
    // Frontiers left without a path or too narrow: margin_may_block's test.
    if (!goal && planning::margin_may_block(p) && p.stats.robot_in_a_lesser_piece && options.back_out_m > 0.0 &&
        !backed_out) {
      // Back the way it came, planning on the way; the first plan with a goal is followed.
      backed_out = true;
      ++out.backs_out;
      const auto way = planning::way_back(trail, options.back_out_m);
      double since = 0.0;
      for (std::size_t k = 1; k < way.size() && !next_plan; ++k) {
        const double length = boost::geometry::distance(way[k - 1], way[k]);
        if (length <= 0.0) continue;
        pose = {way[k].x(), way[k].y(), std::atan2(way[k].y() - way[k - 1].y(), way[k].x() - way[k - 1].x())};
        insert_at(pose.x_m, pose.y_m, pose.theta_rad);
        out.travelled_m += length;
        since += length;
        if (since < options.replan_step_m) continue;
        since = 0.0;
        const MissionSnapshot* on_the_way = snapshot();
        if (!on_the_way) {
          out.error = "planning map failed";
          return out;
        }
        planning::Plan again = plan(on_the_way->map, on_the_way->pose, on_the_way->blacklist, nullptr);
        ++out.plans;
        if (again.best_candidate()) next_plan = std::move(again);
      }
      continue;
    }
    if (!goal) {
      out.done = true;
      break;
    }
    backed_out = false;
    bool seen = false, stopped = false;
    // Along the path: a scan every scan_step_m, a snapshot every replan_step_m.
    const auto& path = goal->path;
    for (std::size_t k = 1; k < path.size(); ++k) {
      const double dx = path[k].x() - path[k - 1].x(), dy = path[k].y() - path[k - 1].y();
      const double length = std::hypot(dx, dy);
      if (length <= 0.0) continue;
      const double heading = std::atan2(dy, dx);
      double clear_m = 0.0;  // along this segment, to the last pose that was clear
      for (double s_m = std::min(options.scan_step_m, length);; s_m = std::min(s_m + options.scan_step_m, length)) {
        const double t = s_m / length;
        const double x = path[k - 1].x() + t * dx, y = path[k - 1].y() + t * dy;
        if (options.robot_radius_m > 0.0 && caster.clearance(x, y, options.robot_radius_m) < options.robot_radius_m) {
          stopped = true;
          out.travelled_m += clear_m;
          break;
        }
        clear_m = s_m;
        pose = {x, y, heading};
        insert_at(pose.x_m, pose.y_m, pose.theta_rad);
        trail.emplace_back(pose.x_m, pose.y_m);
        since_replan += options.scan_step_m;
        if (since_replan >= options.replan_step_m) {
          since_replan = 0.0;
          const MissionSnapshot* on_the_way = snapshot();
          if (!on_the_way) {
            out.error = "planning map failed";
            return out;
          }
          if (options.replan_on_the_way) {
            const planning::GoalFocus focus{goal->position, goal->frontier_point, options.goal_match_radius_m};
            planning::Plan again = (*goal_planner)(on_the_way->map, on_the_way->pose, on_the_way->blacklist,
                                                   options.carry_goal ? &focus : nullptr);
            ++out.plans;
            bool still_there = false;
            for (const auto& c : again.candidates)
              still_there = still_there || (options.carry_goal ? focus.matches(c)
                                                               : boost::geometry::distance(c.position, goal->position) <=
                                                                     options.goal_match_radius_m);
            if (!still_there) {
              seen = true;
              out.travelled_m += s_m;
              // A plan with the way in's margin chooses no goal after its own.
              if (goal_planner == &plan) next_plan = std::move(again);
              break;
            }
          }
        }
        if (s_m >= length) break;
      }
      if (seen || stopped) break;
      out.travelled_m += length;
    }
    if (stopped) {
      ++out.goals;  // taken, and given up
      ++out.guard_stops;
      blacklist.push_back(goal->position);
      continue;
    }
    if (seen) {
      ++out.goals;
      ++out.goals_seen;
      continue;
    }
    // At the goal: look at the frontier, then never choose that goal again.
    pose.theta_rad = std::atan2(goal->frontier_point.y() - pose.y_m, goal->frontier_point.x() - pose.x_m);
    insert_at(pose.x_m, pose.y_m, pose.theta_rad);
    blacklist.push_back(goal->position);
    ++out.goals;
    if (goal->approach && way_in && goal_planner != &way_in) through_frontier = goal->frontier_point;
  }
  auto free_space = map.free_space();
  if (!free_space.ok) out.error = "free space merge failed: " + free_space.error;
  out.free_space = std::move(free_space.polygons);
  return out;
}

// The same on the world file at `world_path`.
inline MissionMaps emulate_mission(const std::string& world_path, const MissionMapsOptions& options,
                                   const MissionPlanner& plan) {
  MissionMaps out;
  const auto world = read_world(world_path, out.error);
  return world ? emulate_mission(*world, options, plan) : out;
}

}  // namespace pex::bench
