#include "explorer_options.hpp"

#include <cmath>
#include <cstdint>
#include <fstream>
#include <optional>
#include <sstream>
#include <variant>

#include "planning/keep_out.hpp"
#include "runtime/config.hpp"

namespace pex::explorer {

namespace {

using runtime::in_range;
using runtime::non_negative;
using runtime::positive;

std::int64_t us_from_ms(int ms) { return static_cast<std::int64_t>(ms) * 1000; }

}  // namespace

ExplorerOptions load_options(runtime::ConfigReader& config) {
  ExplorerOptions o;
  auto& m = o.mission;
  auto& planner = m.planner;
  auto& cspace = planner.cspace;
  auto& follower = m.follower;

  o.pose_channel = config.get<std::string>(
      "pose_channel", o.pose_channel, runtime::registered_channel_of_type("pex.pose_t", "SLAM_POSE or SIM_TRUTH"));
  o.cmd_rate_hz = config.get<double>("cmd_rate_hz", o.cmd_rate_hz, in_range(1.0, 100.0));
  o.state_rate_hz = config.get<double>("state_rate_hz", o.state_rate_hz, in_range(0.1, 100.0));
  o.checkpoint_file = config.get_path("checkpoint_file", o.checkpoint_file, /*must_exist=*/false);
  o.trail_checkpoint_file = config.get_path("trail_checkpoint_file", o.trail_checkpoint_file, /*must_exist=*/false);
  o.checkpoint_period_s = config.get<double>("checkpoint_period_s", o.checkpoint_period_s, in_range(0.1, 3600.0));
  o.map.max_vertices = config.get<std::int64_t>("max_map_vertices", o.map.max_vertices, positive<std::int64_t>());

  // Keep-out lines and areas: what the operator knows and the laser does not
  // see (glass, a drop, a room not to enter), drawn in the file's own frame,
  // in which the robot starts at keep_out_start_pose_m_m_rad.
  const std::string keep_out_file = config.get_path("keep_out_file", "");
  const std::vector<double> keep_out_start =
      config.get<std::vector<double>>("keep_out_start_pose_m_m_rad", {0.0, 0.0, 0.0});
  const double keep_out_line_width_m = config.get<double>("keep_out_line_width_m", 0.05, in_range(0.01, 1.0));
  if (keep_out_start.size() != 3 || !std::isfinite(keep_out_start[0]) || !std::isfinite(keep_out_start[1]) ||
      !std::isfinite(keep_out_start[2]))
    config.fail("keep_out_start_pose_m_m_rad", "needs [x_m, y_m, theta_rad], finite");
  if (!keep_out_file.empty()) {
    std::ifstream in(keep_out_file);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) config.fail("keep_out_file", "cannot read " + keep_out_file);
    auto parsed = planning::parse_keep_out(
        text.str(), keep_out_file, geometry::Pose2{keep_out_start[0], keep_out_start[1], keep_out_start[2]},
        keep_out_line_width_m);
    if (auto* e = std::get_if<planning::KeepOutError>(&parsed)) config.fail("keep_out_file", e->message);
    auto& k = std::get<planning::KeepOut>(parsed);
    o.keep_out_lines = k.lines;
    o.keep_out_areas = k.areas;
    if (!k.obstacles.empty()) o.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(std::move(k.obstacles));
  }

  // The robot and its configuration space.
  cspace.robot_radius_m = config.get<double>("robot_radius_m", cspace.robot_radius_m, in_range(0.01, 5.0));
  cspace.clearance_margin_m =
      config.get<double>("clearance_margin_m", cspace.clearance_margin_m, in_range(0.0, 2.0));
  cspace.points_per_circle = config.get<int>("points_per_circle", cspace.points_per_circle, in_range(4, 360));
  cspace.simplify_epsilon_m =
      config.get<double>("cspace_simplify_epsilon_m", cspace.simplify_epsilon_m, in_range(0.0, 0.5));
  cspace.offset_tile_m = config.get<double>("cspace_offset_tile_m", cspace.offset_tile_m, in_range(0.0, 1000.0));
  cspace.offset_tile_min_vertices = config.get<int>("cspace_offset_tile_min_vertices",
                                                    cspace.offset_tile_min_vertices, non_negative<int>());

  // Goal candidates.
  planner.frontier.sensor_range_m =
      config.get<double>("sensor_range_m", planner.frontier.sensor_range_m, in_range(0.1, 100.0));
  planner.frontier.min_frontier_length_m =
      config.get<double>("min_frontier_length_m", planner.frontier.min_frontier_length_m, non_negative<double>());
  planner.candidate_snap_distance_m =
      config.get<double>("candidate_snap_distance_m", planner.candidate_snap_distance_m, positive<double>());
  planner.start_snap_distance_m =
      config.get<double>("start_snap_distance_m", planner.start_snap_distance_m, positive<double>());
  planner.start_sliver_area_m2 =
      config.get<double>("start_sliver_area_m2", planner.start_sliver_area_m2, in_range(0.0, 10.0));
  planner.blacklist_radius_m =
      config.get<double>("blacklist_radius_m", planner.blacklist_radius_m, non_negative<double>());
  planner.turn_cost_m_per_rad =
      config.get<double>("turn_cost_m_per_rad", planner.turn_cost_m_per_rad, non_negative<double>());
  planner.trail_corridor_m = config.get<double>("trail_corridor_m", planner.trail_corridor_m, in_range(0.0, 0.5));
  planner.reach_past_frontier_m =
      config.get<double>("reach_past_frontier_m", planner.reach_past_frontier_m, in_range(0.0, 1.0));
  planner.min_enclosed_area_m2 =
      config.get<double>("min_enclosed_area_m2", planner.min_enclosed_area_m2, in_range(0.0, 1000.0));
  planner.enclosed_goal_range_m =
      config.get<double>("enclosed_goal_range_m", planner.enclosed_goal_range_m, in_range(0.0, 1000.0));
  planner.bay_max_area_m2 = config.get<double>("bay_max_area_m2", planner.bay_max_area_m2, in_range(0.0, 1000.0));
  planner.bay_max_lid_m = config.get<double>("bay_max_lid_m", planner.bay_max_lid_m, in_range(0.01, 20.0));
  planner.narrow_gap_tolerance_m =
      config.get<double>("narrow_gap_tolerance_m", planner.narrow_gap_tolerance_m, in_range(0.0, 1.0));
  if (planner.narrow_gap_tolerance_m >= cspace.robot_radius_m)
    throw runtime::ConfigError(config.origin() +
                               ": narrow_gap_tolerance_m must be less than robot_radius_m (the narrower disk it "
                               "checks gaps with keeps a radius)");
  if (planner.reach_past_frontier_m >= cspace.robot_radius_m)
    throw runtime::ConfigError(config.origin() +
                               ": reach_past_frontier_m must be less than robot_radius_m (the disk reaches past a "
                               "frontier by its radius at most)");
  if (planner.candidate_snap_distance_m < cspace.robot_radius_m + cspace.clearance_margin_m)
    throw runtime::ConfigError(config.origin() +
                               ": candidate_snap_distance_m must be at least robot_radius_m + clearance_margin_m "
                               "(the C-space lies that far from every frontier)");

  // Path following.
  follower.max_speed_mps = config.get<double>("max_speed_mps", follower.max_speed_mps, in_range(0.01, 5.0));
  follower.min_speed_mps = config.get<double>("min_speed_mps", follower.min_speed_mps, non_negative<double>());
  follower.max_omega_radps = config.get<double>("max_omega_radps", follower.max_omega_radps, in_range(0.01, 10.0));
  follower.max_accel_mps2 = config.get<double>("max_accel_mps2", follower.max_accel_mps2, in_range(0.01, 20.0));
  follower.max_angular_accel_radps2 =
      config.get<double>("max_angular_accel_radps2", follower.max_angular_accel_radps2, in_range(0.01, 50.0));
  follower.lookahead_m = config.get<double>("lookahead_m", follower.lookahead_m, in_range(0.05, 10.0));
  follower.turn_in_place_rad =
      config.get<double>("turn_in_place_rad", follower.turn_in_place_rad, in_range(0.05, 3.2));
  follower.turn_in_place_exit_rad =
      config.get<double>("turn_in_place_exit_rad", follower.turn_in_place_exit_rad, in_range(0.01, 3.2));
  follower.turn_gain_per_s = config.get<double>("turn_gain_per_s", follower.turn_gain_per_s, in_range(0.1, 20.0));
  follower.goal_tolerance_m = config.get<double>("goal_tolerance_m", follower.goal_tolerance_m, in_range(0.01, 5.0));
  follower.corner_tolerance_m =
      config.get<double>("corner_tolerance_m", follower.corner_tolerance_m, in_range(0.01, 2.0));
  if (follower.turn_in_place_exit_rad > follower.turn_in_place_rad)
    throw runtime::ConfigError(config.origin() + ": turn_in_place_exit_rad must not exceed turn_in_place_rad");

  // Mission.
  m.autostart = config.get<bool>("autostart", m.autostart);
  planner.strategy = *planning::parse_goal_strategy(config.get<std::string>(
      "goal_strategy", planning::to_string(planner.strategy), runtime::one_of({"greedy", "tour"})));
  planner.tour.horizon_candidates =
      config.get<int>("tour_horizon_candidates", planner.tour.horizon_candidates, runtime::in_range(0, 1000));
  planner.tour.one_per_chain = config.get<bool>("tour_one_per_chain", planner.tour.one_per_chain);
  planner.tour.max_first_leg_ratio = config.get<double>("tour_max_first_leg_ratio", planner.tour.max_first_leg_ratio,
                                                        runtime::in_range(0.0, 1000.0));
  planner.tour.first_leg_slack_m =
      config.get<double>("tour_first_leg_slack_m", planner.tour.first_leg_slack_m, runtime::in_range(0.0, 1000.0));
  m.plan_timeout_us =
      us_from_ms(config.get<int>("plan_timeout_ms", static_cast<int>(m.plan_timeout_us / 1000), in_range(100, 600'000)));
  m.replan_period_us =
      us_from_ms(config.get<int>("replan_period_ms", static_cast<int>(m.replan_period_us / 1000), in_range(50, 60'000)));
  m.pose_timeout_us =
      us_from_ms(config.get<int>("pose_timeout_ms", static_cast<int>(m.pose_timeout_us / 1000), in_range(10, 60'000)));
  m.map_timeout_us =
      us_from_ms(config.get<int>("map_timeout_ms", static_cast<int>(m.map_timeout_us / 1000), in_range(100, 600'000)));
  m.scan_timeout_us = us_from_ms(config.get<int>("scan_timeout_ms", 500, in_range(0, 60'000)));
  m.progress_timeout_us = us_from_ms(
      config.get<int>("progress_timeout_ms", static_cast<int>(m.progress_timeout_us / 1000), in_range(1000, 3'600'000)));
  m.progress_min_m = config.get<double>("progress_min_m", m.progress_min_m, positive<double>());
  m.goal_match_radius_m = config.get<double>("goal_match_radius_m", m.goal_match_radius_m, positive<double>());
  m.max_consecutive_failures =
      config.get<int>("max_consecutive_failures", m.max_consecutive_failures, in_range(1, 1000));
  m.done_confirmations = config.get<int>("done_confirmations", m.done_confirmations, in_range(1, 100));
  m.look_tolerance_rad = config.get<double>("look_tolerance_rad", m.look_tolerance_rad, in_range(0.0, 3.2));
  m.max_travel_step_m = config.get<double>("max_travel_step_m", m.max_travel_step_m, positive<double>());
  m.tight_fallback = config.get<bool>("tight_fallback", m.tight_fallback);
  m.look_around = config.get<bool>("look_around", m.look_around);
  m.back_out_m = config.get<double>("back_out_m", m.back_out_m, in_range(0.0, 1000.0));
  m.way_in_margin_m = config.get<double>("way_in_margin_m", m.way_in_margin_m, in_range(0.0, 1.0));
  m.look_around_max_us = static_cast<std::int64_t>(
      config.get<double>("look_around_max_s", static_cast<double>(m.look_around_max_us) * 1e-6, in_range(1.0, 600.0)) * 1e6);
  o.scan_guard = config.get<bool>("scan_guard", o.scan_guard);
  o.guard.body_radius_m = config.get<double>("guard_body_radius_m", o.guard.body_radius_m, in_range(0.01, 5.0));
  o.guard.margin_m = config.get<double>("guard_margin_m", o.guard.margin_m, in_range(0.0, 1.0));
  o.guard.side_margin_m = config.get<double>("guard_side_margin_m", o.guard.side_margin_m, in_range(0.0, 1.0));
  o.guard.creep_speed_mps = config.get<double>("guard_creep_speed_mps", o.guard.creep_speed_mps, in_range(0.0, 5.0));
  o.guard.max_decel_mps2 = config.get<double>("guard_decel_mps2", o.guard.max_decel_mps2, in_range(0.01, 20.0));
  o.guard.latency_s = config.get<double>("guard_latency_ms", o.guard.latency_s * 1e3, in_range(0.0, 2000.0)) * 1e-3;
  o.guard_scan.wall_end_reach_m =
      config.get<double>("guard_wall_end_reach_m", o.guard_scan.wall_end_reach_m, in_range(0.0, 0.5));
  o.guard_scan.wall_end_jump_m =
      config.get<double>("guard_wall_end_jump_m", o.guard_scan.wall_end_jump_m, in_range(0.001, 10.0));
  o.guard_scan.map_walls_m = config.get<double>("guard_map_walls_m", o.guard_scan.map_walls_m, in_range(0.0, 30.0));
  o.guard_block_us = static_cast<std::int64_t>(
      config.get<double>("guard_block_ms", static_cast<double>(o.guard_block_us) * 1e-3, in_range(0.0, 60000.0)) * 1e3);
  m.max_guard_blocks_per_goal =
      config.get<int>("max_guard_blocks_per_goal", m.max_guard_blocks_per_goal, in_range(0, 1000));
  auto& marks = o.guard_marks;
  marks.lifetime_s = config.get<double>("guard_mark_lifetime_s", marks.lifetime_s, in_range(0.0, 1e6));
  marks.holding_depth_m = config.get<double>("guard_mark_depth_m", marks.holding_depth_m, in_range(0.0, 1.0));
  marks.max_reach_m = config.get<double>("guard_mark_reach_m", marks.max_reach_m, in_range(0.0, 5.0));
  marks.width_m = config.get<double>("guard_mark_width_m", marks.width_m, in_range(0.01, 1.0));
  marks.max_marks = config.get<int>("max_guard_marks", marks.max_marks, in_range(0, 1000));
  o.max_beams = static_cast<std::size_t>(
      config.get<int>("max_beams", static_cast<int>(o.max_beams), in_range(1, 1 << 20)));
  o.min_scan_returns = config.get<int>("min_scan_returns", o.min_scan_returns, in_range(0, 1 << 20));
  // A restarted explorer may find the base still driving its predecessor's
  // last command: the guard starts from the top speed the explorer commands.
  o.guard.start_speed_mps = o.mission.follower.max_speed_mps;
  o.live_view.range_m = config.get<double>("live_view_range_m", o.live_view.range_m, in_range(0.0, 30.0));
  o.live_view.no_return_stops_at_walls =
      config.get<bool>("live_view_no_return_stops_at_walls", o.live_view.no_return_stops_at_walls);
  o.live_view_when_stuck_only = config.get<bool>("live_view_when_stuck_only", o.live_view_when_stuck_only);
  o.blind_beams.after_stopped_scans =
      config.get<int>("blind_after_stopped_scans", o.blind_beams.after_stopped_scans, in_range(0, 1000));
  o.blind_beams.no_free_space_before_first_echo =
      config.get<bool>("no_free_space_before_first_echo", o.blind_beams.no_free_space_before_first_echo);
  return o;
}

}  // namespace pex::explorer
