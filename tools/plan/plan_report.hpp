#pragma once
// pex-plan's output: a plan (planning::plan_exploration) on a logged MAP as
// text (every candidate, reachable or why not) and as SVG (free space,
// obstacle and frontier edges, the C-space pieces, candidates, the path).
#include <string>
#include <vector>

#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>

#include "planning/cspace.hpp"
#include "planning/exploration_planner.hpp"

namespace pex::plan_tool {

// One line per fact: map and pose, C-space pieces (area, which one holds the
// robot), then each candidate: frontier point, position, approach or not,
// reachable with path length and cost, or "no path", and the best one.
std::string describe(const pex::polygon_map_t& map, const pex::pose_t& pose,
                     const planning::ConfigurationSpace& cspace, const planning::Plan& plan);

// The mission's blacklist as an EXPLORE_STATE shows it: the frontier goals
// it lists as visited or given up (pex-plan --blacklist-from-log). Entries
// past the shortest of the frontier arrays (a malformed message) are ignored.
std::vector<planning::Point> blacklist_of(const pex::explore_state_t& state);

std::string to_svg(const mapping::TypedMultiPolygon& map, const geometry::Pose2& robot,
                   const planning::ConfigurationSpace& cspace, const planning::Plan& plan,
                   double pixels_per_m = 40.0);

}  // namespace pex::plan_tool
