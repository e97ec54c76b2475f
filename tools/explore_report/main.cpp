// pex-explore-report --world worlds/X.wkt --log run.lcm [--robot-radius-m 0.25]
//   [--map-frame start|world] [--wall-tolerance-m 0.1] [--credit-obstacle-band-m 0]
//   [--scored-map auto|MAP_FREE|MAP]
//   [--start-pose X Y THETA]
//   [--json-out FILE] [--svg FILE]
// Scores an exploration run recorded with lcm-logger against its world: one
// JSON line (the exploration benchmark's) on stdout and in --json-out; what
// was read and how the map decoded on stderr. Channels missing from the log
// give null fields. Exit codes: 0 done, 64 bad command line, 65 bad world
// file, empty log or start pose in collision, 66 unreadable file, 70 the
// geometry failed, 73 an output cannot be written.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/command_line.hpp"
#include "report.hpp"

namespace {

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "pex-explore-report: %s\n", message.c_str());
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Score an exploration run (LCM log) against its world: the benchmark's JSON line",
               "pex-explore-report"};
  std::string world_path, log_path, map_frame = "start", json_out, svg_out;
  pex::explore_report::ReportOptions options;
  std::vector<double> start_pose;
  app.add_option("--world", world_path, "world file the run explored (worlds/*.wkt)")->required();
  app.add_option("--log", log_path, "LCM log of the run (lcm-logger)")->required();
  app.add_option("--robot-radius-m", options.robot_radius_m, "robot radius (config/sim.toml [base])")
      ->check(CLI::PositiveNumber);
  app.add_option("--map-frame", map_frame,
                 "frame of the MAP: start (SLAM / odometry: origin at the start pose) or world (pose_source = sim_truth)")
      ->check(CLI::IsMember({"start", "world"}));
  app.add_option("--wall-tolerance-m", options.wall_tolerance_m, "obstacle edges this close to a wall are on it")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--credit-obstacle-band-m", options.obstacle_band_credit_m,
                 "count reachable space this close to a map obstacle edge as mapped (MAP is free space minus "
                 "polygon_mapper's obstacle band; its obstacle_outer_m is 0.10); default 0: the map as published")
      ->check(CLI::NonNegativeNumber);
  std::string scored_map = "auto";
  app.add_option("--scored-map", scored_map,
                 "the map scored: MAP_FREE (the explored free space), MAP (the planning map: free space minus the "
                 "obstacle band), auto (MAP_FREE if the log has it, else MAP)")
      ->check(CLI::IsMember({"auto", "MAP_FREE", "MAP"}));
  app.add_option("--start-pose", start_pose, "X_M Y_M THETA_RAD: the start pose, if not the world's START line")
      ->expected(3);
  std::string slam_poses_from;
  app.add_option("--slam-poses-from", slam_poses_from,
                 "take SLAM_POSE for the pose audit from this log instead of the run's: the run's record replayed "
                 "through another SLAM configuration (pex-slam --log RUN.lcm --out THIS.lcm)");
  app.add_option("--json-out", json_out, "also write the JSON line to this file");
  std::string pose_errors_out;
  app.add_option("--pose-errors-out", pose_errors_out,
                 "write the pose audit's pairs to this file, one line each: t_s slam_x slam_y slam_theta truth_x truth_y "
                 "truth_theta error_m heading_error_deg (world frame; where SLAM went wrong, and when)");
  app.add_option("--svg", svg_out, "draw the world, the reachable space and the map (red: missed, violet: not reachable, gold: beyond the walls) to this SVG");
  if (const auto code = pex::cli::parse_command_line(app, "pex-explore-report", argc, argv)) return *code;

  std::ifstream world_file(world_path);
  if (!world_file) return fail(66, "cannot read world file " + world_path);
  std::stringstream text;
  text << world_file.rdbuf();
  auto parsed = pex::sim::parse_world(text.str(), world_path);
  if (auto* error = std::get_if<pex::sim::WorldError>(&parsed)) return fail(65, error->message);
  const auto& world = std::get<pex::sim::World>(parsed);
  pex::geometry::Pose2 start = world.start;
  if (!start_pose.empty()) start = {start_pose[0], start_pose[1], start_pose[2]};
  if (map_frame == "start") options.map_in_world = start;
  using pex::explore_report::ScoredMap;
  options.scored_map = scored_map == "MAP_FREE" ? ScoredMap::kFreeSpace
                       : scored_map == "MAP"    ? ScoredMap::kPlanningMap
                                                : ScoredMap::kAuto;

  std::string error;
  std::optional<pex::explore_report::LogContents> replayed;
  if (!slam_poses_from.empty()) {
    replayed = pex::explore_report::read_log(slam_poses_from, &error);
    if (!replayed) return fail(error.rfind("cannot open", 0) == 0 ? 66 : 65, error);
  }
  auto log = pex::explore_report::read_log(log_path, &error);
  if (!log) return fail(error.rfind("cannot open", 0) == 0 ? 66 : 65, error);
  if (replayed) log->slam_poses = std::move(replayed->slam_poses);

  pex::mapping::MultiPolygon reachable, world_free;
  try {
    reachable = pex::evaluation::reachable_free_space(world, options.robot_radius_m, start);
    // The free region holding the start: centres 1 mm clear of every wall.
    world_free = pex::evaluation::configuration_free_component(world, 0.001, start);
  } catch (const std::exception& e) {
    return fail(70, std::string("reachable free space: ") + e.what());
  }
  if (reachable.empty())
    return fail(65, "the start pose (" + std::to_string(start.x_m) + ", " + std::to_string(start.y_m) +
                        ") is within robot_radius_m of a wall: nothing is reachable");

  const std::string world_name = std::filesystem::path(world_path).stem().string();
  pex::mapping::TypedMultiPolygon map_world;
  const auto report = pex::explore_report::make_report(world_name, *log, world, reachable, options, &map_world, &world_free);

  std::fprintf(stderr,
               "pex-explore-report: %lld events (%lld undecodable); MAP %s, MAP_FREE %s (scored: %s), EXPLORE_STATE %s, SIM_CLOCK %s, "
               "explorer DAEMON_STATUS %s; map frame %s; mission_time_s %s\n",
               static_cast<long long>(log->events), static_cast<long long>(log->rejected),
               log->map ? "yes" : "none", log->free_space ? "yes" : "none",
               report.scored_map ? report.scored_map->c_str() : "none", log->explore_state ? "yes" : "none", log->sim_clock ? "yes" : "none",
               log->explorer_status ? "yes" : "none", map_frame.c_str(),
               log->explore_state ? std::to_string(log->explore_state->mission_time_s).c_str() : "none");
  if (!report.map_error.empty())
    std::fprintf(stderr, "pex-explore-report: the last %s does not decode: %s\n", report.scored_map->c_str(),
                 report.map_error.c_str());
  if (report.map_polygons_dropped > 0)
    std::fprintf(stderr, "pex-explore-report: %d invalid map polygons dropped (not counted as mapped)\n",
                 report.map_polygons_dropped);

  const std::string line = pex::explore_report::to_json(report);
  std::printf("%s\n", line.c_str());
  if (!json_out.empty()) {
    std::ofstream out(json_out);
    out << line << '\n';
    if (!out) return fail(73, "cannot write " + json_out);
  }
  if (!pose_errors_out.empty()) {
    std::ofstream out(pose_errors_out);
    out << "# t_s slam_x_m slam_y_m slam_theta_rad truth_x_m truth_y_m truth_theta_rad error_m heading_error_deg\n";
    char row[256];
    for (const auto& pair : pex::explore_report::pose_errors(*log, options.map_in_world)) {
      std::snprintf(row, sizeof row, "%.3f %.3f %.3f %.4f %.3f %.3f %.4f %.3f %.2f\n", static_cast<double>(pair.utime) * 1e-6,
                    pair.slam_in_world.x_m, pair.slam_in_world.y_m, pair.slam_in_world.theta_rad, pair.truth.x_m,
                    pair.truth.y_m, pair.truth.theta_rad, pair.error_m, pair.heading_error_rad * 180.0 / std::numbers::pi);
      out << row;
    }
    if (!out) return fail(73, "cannot write " + pose_errors_out);
  }
  if (!svg_out.empty()) {
    std::ofstream out(svg_out);
    out << pex::explore_report::to_svg(world, reachable, map_world, start, options.robot_radius_m,
                                       options.wall_tolerance_m, &world_free);
    if (!out) return fail(73, "cannot write " + svg_out);
  }
  return 0;
}
