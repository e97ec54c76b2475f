#pragma once
// pex-explore-report's core: the last messages of an exploration run's LCM
// log, scored against the world file, as the exploration benchmark's JSON
// line (and an SVG that shows what was missed).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/sim_clock_t.hpp>

#include "evaluation/exploration_metrics.hpp"

namespace pex::explore_report {

struct StampedPose {
  std::int64_t utime = 0;
  geometry::Pose2 pose;
};

// The last decodable message of each channel the report needs, and the
// poses SLAM published and the simulator's truth, for the pose audit.
struct LogContents {
  std::vector<StampedPose> slam_poses;  // SLAM_POSE (MAP frame), in log order
  std::vector<StampedPose> truth;       // SIM_TRUTH (world frame), in log order
  std::optional<pex::polygon_map_t> map;              // MAP (the planning map)
  std::optional<pex::polygon_map_t> free_space;       // MAP_FREE (the explored free space)
  std::optional<pex::explore_state_t> explore_state;  // EXPLORE_STATE
  std::optional<pex::sim_clock_t> sim_clock;          // SIM_CLOCK
  std::optional<pex::daemon_status_t> explorer_status;  // DAEMON_STATUS with name "explorer"
  std::int64_t events = 0;    // all events in the log
  std::int64_t rejected = 0;  // events on those channels that did not decode
};

// Reads the log at `path`. nullopt (and *error set) when the file cannot be
// opened or holds no LCM event at all.
std::optional<LogContents> read_log(const std::string& path, std::string* error);

// A SLAM_POSE and the simulator's truth nearest it in time (within 20 ms),
// the MAP frame placed in the world by map_in_world: the pose audit's pairs
// (Report's slam_error_*), in the log's order.
struct PoseError {
  std::int64_t utime = 0;         // the SLAM_POSE's stamp
  geometry::Pose2 slam_in_world;  // the published pose, in the world frame
  geometry::Pose2 truth;          // SIM_TRUTH
  double error_m = 0.0;           // distance between the two
  double heading_error_rad = 0.0;  // slam minus truth, wrapped
};
std::vector<PoseError> pose_errors(const LogContents& log, const geometry::Pose2& map_in_world);

// The lower-case name of an explore_state_t phase ("done",
// "done_with_unreachable", ...), "unknown_<n>" for others.
std::string phase_name(std::int8_t phase);

// Which map is scored. The explored free space (MAP_FREE) is what the robot
// has seen; MAP is it minus polygon_mapper's obstacle band, which on a
// zero-thickness wall takes obstacle_outer_m of floor the robot has seen from
// the wall's other side. kAuto: MAP_FREE when the log has it, else MAP (logs
// from before MAP_FREE).
enum class ScoredMap { kAuto, kPlanningMap, kFreeSpace };

struct ReportOptions {
  ScoredMap scored_map = ScoredMap::kAuto;
  double robot_radius_m = 0.25;
  double wall_tolerance_m = 0.1;
  // Reachable space this close to a map obstacle edge counts as mapped
  // (evaluation::score_map): the obstacle band the mapper cuts out of MAP.
  double obstacle_band_credit_m = 0.0;
  evaluation::CreditNear credit_near = evaluation::CreditNear::kMapObstacleEdges;
  // The pose of the MAP frame's origin in the world: the robot's start pose
  // (SLAM / odometry frame) or the identity (pose_source = "sim_truth").
  geometry::Pose2 map_in_world;
};

// One benchmark line; nullopt fields are printed as null.
struct Report {
  std::string world;
  std::optional<std::string> strategy, phase;
  std::optional<std::string> scored_map;  // the channel scored: "MAP_FREE" or "MAP"
  std::optional<double> sim_time_s, path_m, explored_m2, reachable_m2, coverage, iou, obstacle_on_wall;
  std::optional<std::int64_t> collisions, goals, plans;  // goals: reached (there, facing the frontier)
  // The explorer's other goal outcomes (its DAEMON_STATUS counters): seen
  // (its frontier explored on the way, before the robot got there), given
  // up (blocked, no progress or overdue). Null when the log holds no such counter.
  std::optional<std::int64_t> goals_seen, goals_given_up;
  std::optional<double> plan_ms_p50, plan_ms_p99, control_ms_p99;
  std::optional<double> plan_cpu_ms_p50, plan_cpu_ms_p99;  // the planner thread's CPU time
  // The same p99 and the count of plans by what each was for (select,
  // follow, tight, home: planning::PlanKind); empty when the log's explorer
  // did not count them.
  struct PlansOfKind {
    std::string kind;
    std::optional<std::int64_t> plans;
    std::optional<double> cpu_ms_p99;
  };
  std::vector<PlansOfKind> plans_by_kind;
  // Where the map's free space that is not reachable lies (with world_free):
  // outside the world's free region holding the start (beyond a wall, inside
  // a solid: the map is wrong there), or inside it where the robot's disk
  // cannot sweep (room corners, notches of ragged walls, space seen through a
  // gap narrower than the robot: the map is right there, the IoU counts it
  // against the map all the same).
  std::optional<double> map_outside_free_m2, map_unreachable_free_m2;
  // SLAM_POSE against SIM_TRUTH at the same time (within 20 ms), the MAP
  // frame placed in the world as the map is: how far the published pose was
  // from the truth, on average and at worst, and its heading error. The map
  // inherits these errors: scans inserted at wrong poses draw walls off the
  // world's (map_outside_free_m2).
  std::optional<double> slam_error_mean_m, slam_error_max_m, slam_heading_error_mean_deg;
  // The mean error once the whole SLAM trajectory is moved by the one rigid
  // motion that fits it best to the truth (geometry::best_rigid_fit): small
  // while the mean above is large means a consistent map in a frame turned
  // at the start; large means the map bends (a loop not closed).
  std::optional<double> slam_error_aligned_mean_m;
  // Not in the line (stderr): how the map decoded.
  int map_polygons_dropped = 0;
  std::string map_error;  // the last MAP did not decode at all
};

// Fills the report from the log and the world's reachable free space
// (evaluation::reachable_free_space, computed by the caller). `map_world`,
// if given, receives the decoded map moved into the world frame.
// `world_free`, if given, is the world's free region holding the start
// (evaluation::configuration_free_component with a radius of a millimetre or
// two): it splits the map's unreachable free space in two (Report above).
Report make_report(const std::string& world_name, const LogContents& log, const sim::World& world,
                   const mapping::MultiPolygon& reachable, const ReportOptions& options,
                   mapping::TypedMultiPolygon* map_world = nullptr,
                   const mapping::MultiPolygon* world_free = nullptr);

// The JSON line (no trailing newline), keys in the benchmark's order.
std::string to_json(const Report& report);

// SVG: the reachable space light green, the part of it the map missed red,
// mapped free space outside it violet, the map's free space blue over the
// reachable, map obstacle edges dark blue (magenta where more than 1 % of
// an edge is farther than wall_tolerance_m from every wall), frontier edges
// orange, world walls black, the robot's disk at the start green; y up.
// With world_free (make_report), the map's free space outside the world's
// free region (beyond a wall) is drawn gold over the violet.
std::string to_svg(const sim::World& world, const mapping::MultiPolygon& reachable,
                   const mapping::TypedMultiPolygon& map_world, const geometry::Pose2& start,
                   double robot_radius_m, double wall_tolerance_m, const mapping::MultiPolygon* world_free = nullptr);

}  // namespace pex::explore_report
