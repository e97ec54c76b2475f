#include "planning/exploration_planner.hpp"

#include <cmath>
#include <numbers>

namespace pex::planning {

double wrap_angle(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * std::numbers::pi);
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

int Plan::reachable_count() const {
  int n = 0;
  for (const auto& c : candidates) n += (c.reachable && !c.blacklisted) ? 1 : 0;
  return n;
}

Plan plan_exploration(const TypedMultiPolygon& map, const Pose2& robot, const std::vector<Point>& blacklist,
                      const PlannerOptions& options) {
  Plan plan;
  if (!std::isfinite(robot.x) || !std::isfinite(robot.y) || !std::isfinite(robot.theta)) {
    plan.error = "robot pose is not finite";
    return plan;
  }
  ConfigurationSpace cspace;
  const auto built = cspace.build(map, options.cspace);
  if (!built.ok) {
    plan.error = built.error;
    return plan;
  }
  plan.stats.cspace_vertices = static_cast<int>(mapping::vertex_count(cspace.polygons()));
  plan.stats.reflex_nodes = static_cast<int>(cspace.reflex_nodes().size());

  // 1. Candidates on the frontiers, moved into the C-space.
  const auto chains = frontier_chains(map);
  plan.stats.frontier_chains = static_cast<int>(chains.size());
  const auto points = frontier_candidates(chains, options.frontier, &plan.stats.chains_too_short);
  std::vector<Point> targets;
  for (const auto& fp : points) {
    const auto inside = cspace.nearest_interior_point(fp.point, options.candidate_snap_distance_m);
    if (!inside) {
      ++plan.stats.candidates_not_in_cspace;
      continue;
    }
    GoalCandidate c;
    c.frontier_point = fp.point;
    c.position = *inside;
    c.chain = fp.chain;
    c.chain_length_m = fp.chain_length_m;
    for (const auto& b : blacklist)
      if (distance(b, c.position) <= options.blacklist_radius_m) c.blacklisted = true;
    plan.candidates.push_back(std::move(c));
    targets.push_back(*inside);
  }

  // 2. The robot's own node.
  const Point robot_point(robot.x, robot.y);
  const auto start = cspace.nearest_interior_point(robot_point, options.start_snap_distance_m);
  if (!start) {
    plan.error = "the robot is not within " + std::to_string(options.start_snap_distance_m) +
                 " m of the configuration space";
    return plan;
  }

  // 3. Shortest paths and the best candidate.
  const auto paths = shortest_paths(cspace, *start, targets);
  plan.stats.segment_tests = paths.segment_tests;
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    auto& c = plan.candidates[i];
    if (!std::isfinite(paths.length_m[i])) continue;
    c.reachable = true;
    c.path = paths.path[i];
    c.path_length_m = paths.length_m[i];
    if (distance(robot_point, *start) > 0.0) {
      c.path.insert(c.path.begin(), robot_point);
      c.path_length_m += distance(robot_point, *start);
    }
    double turn = 0.0;
    if (c.path.size() >= 2) {
      const Point& a = c.path[0];
      const Point& b = c.path[1];
      if (distance(a, b) > 1e-9) turn = std::abs(wrap_angle(std::atan2(b.y() - a.y(), b.x() - a.x()) - robot.theta));
    }
    c.cost = c.path_length_m + options.turn_cost_m_per_rad * turn;
    if (c.blacklisted) continue;
    if (plan.best < 0 || c.cost < plan.candidates[static_cast<std::size_t>(plan.best)].cost)
      plan.best = static_cast<int>(i);
  }
  plan.ok = true;
  return plan;
}

}  // namespace pex::planning
