// pex-plan --log IN.lcm [--config explorer.toml] [--pose-channel SIM_TRUTH]
//          [--utime T] [--tight] [--svg OUT.svg]
// Runs the explorer's planner, offline, on a MAP of an LCM log: the last MAP
// (or the last one at or before --utime) and the newest pose on the pose
// channel at that time, with the planner options of an explorer config. It
// prints every frontier goal candidate (where, reachable or why not, path
// length) and the C-space pieces, and can draw map, C-space, candidates and
// the chosen path to SVG: how to see why a mission ended where it did.
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <lcm/lcm-cpp.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/pose_t.hpp>

#include "explorer_node.hpp"
#include "cli/command_line.hpp"
#include "explorer_options.hpp"
#include "map_message.hpp"
#include "plan_report.hpp"
#include "planning/cspace.hpp"
#include "planning/live_view.hpp"
#include "runtime/channels.hpp"
#include "runtime/config.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Run the explorer's planner on a logged MAP and show why it chose what it chose"};
  std::string log_path, config_path, map_channel{pex::runtime::channels::kMap}, pose_channel{"SLAM_POSE"}, svg_path;
  std::int64_t at_utime = -1;
  bool tight = false;
  app.add_option("--log", log_path, "LCM log with MAP and pose messages")->required();
  app.add_option("--config", config_path, "explorer config (planner options); default: the defaults in code");
  app.add_option("--map-channel", map_channel, "channel of the pex.polygon_map_t messages");
  app.add_option("--pose-channel", pose_channel, "channel of the robot's pex.pose_t (SLAM_POSE, SIM_TRUTH)");
  app.add_option("--utime", at_utime, "plan on the last MAP at or before this message utime (default: the last MAP)");
  app.add_flag("--tight", tight, "plan without the clearance margin (the explorer's tight fallback)");
  app.add_option("--svg", svg_path, "draw map, C-space, candidates and the chosen path");
  if (const auto code = pex::cli::parse_command_line(app, "pex-plan", argc, argv)) return *code;

  pex::explorer::ExplorerOptions options;
  try {
    auto config = config_path.empty() ? pex::runtime::ConfigReader() : pex::runtime::ConfigReader::from_file(config_path);
    options = pex::explorer::load_options(config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pex-plan: %s\n", e.what());
    return EX_CONFIG;  // 78: a bad --config, as the daemons
  }
  pex::planning::PlannerOptions planner = options.mission.planner;
  if (tight) planner.cspace.clearance_margin_m = 0.0;

  lcm::LogFile log(log_path, "r");
  if (!log.good()) {
    std::fprintf(stderr, "pex-plan: cannot read %s\n", log_path.c_str());
    return EX_NOINPUT;
  }
  std::optional<pex::polygon_map_t> map;
  std::optional<pex::pose_t> pose;           // newest pose up to the chosen map
  std::optional<pex::pose_t> pose_pending;   // newest pose overall, taken with the next map
  std::optional<pex::laser_scan_t> scan, scan_pending;  // the same for LIDAR_SCAN (the live view)
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
    if (e->channel == pex::runtime::channels::kLidarScan) {
      pex::laser_scan_t s;
      if (s.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && s.utime > at_utime) continue;
      scan_pending = std::move(s);
    } else if (e->channel == pose_channel) {
      pex::pose_t p;
      if (p.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && p.utime > at_utime) continue;
      pose_pending = p;
    } else if (e->channel == map_channel) {
      pex::polygon_map_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && m.utime > at_utime) continue;
      map = std::move(m);
      pose = pose_pending;
      scan = scan_pending;
    }
  }
  if (!map || !pose) {
    std::fprintf(stderr, "pex-plan: no %s with a %s before it in %s\n", map_channel.c_str(), pose_channel.c_str(),
                 log_path.c_str());
    return EX_DATAERR;
  }
  const auto decoded = pex::explorer::decode_map(*map, options.map);
  if (!decoded.ok) {
    std::fprintf(stderr, "pex-plan: the MAP is bad input: %s\n", decoded.error.c_str());
    return EX_DATAERR;
  }
  const pex::geometry::Pose2 robot{pose->x, pose->y, pose->theta};
  // As the explorer plans: the newest scan's live view united in (live_view_range_m).
  const auto live = scan ? pex::explorer::live_view_of(*scan, robot, options.live_view) : nullptr;
  const auto planned_on = live ? pex::planning::with_live_view(decoded.polygons, *live) : decoded.polygons;
  const auto plan = pex::planning::plan_exploration(decoded.polygons, robot, {}, planner, live ? &planned_on : nullptr);
  pex::planning::ConfigurationSpace cspace;
  cspace.build(planned_on, planner.cspace);
  std::printf("live view: %s\n", live ? "united into the map (newest LIDAR_SCAN)"
                                      : (scan ? "off (live_view_range_m = 0)" : "none (no LIDAR_SCAN)"));
  std::printf("%s", pex::plan_tool::describe(*map, *pose, cspace, plan).c_str());
  if (!svg_path.empty()) {
    std::ofstream svg(svg_path);
    svg << pex::plan_tool::to_svg(planned_on, robot, cspace, plan);
    svg.close();
    if (!svg) {
      std::fprintf(stderr, "pex-plan: cannot write %s\n", svg_path.c_str());
      return EX_CANTCREAT;
    }
    std::printf("wrote %s\n", svg_path.c_str());
  }
  return plan.ok ? 0 : 1;
}
