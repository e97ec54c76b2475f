// pex-plan --log IN.lcm [--config explorer.toml] [--pose-channel SIM_TRUTH]
//          [--utime T] [--tight] [--blacklist-from-log] [--svg OUT.svg]
// Runs the explorer's planner, offline, on a MAP of an LCM log: the last MAP
// (or the last one at or before --utime) and the newest pose on the pose
// channel at that time, with the planner options of an explorer config. It
// prints every frontier goal candidate (where, reachable or why not, path
// length) and the C-space pieces, and can draw map, C-space, candidates and
// the chosen path to SVG: how to see why a mission ended where it did.
// --blacklist-from-log takes the goals the log's last EXPLORE_STATE (up to
// the map) lists as visited or given up as the blacklist, as the mission had it.
//
// pex-plan --log IN.lcm --every-map [--config ...] [--strategy tour] [--plans-csv F] [--from-utime T] [--tight]
// Plans, as the explorer's worker does (the newest pose and LIDAR_SCAN's live
// view at each MAP), on every MAP of a mission's log, and prints the planner's
// CPU time per plan (p50 / p99 / max) and the slowest maps' utimes: the plan-time
// benchmark on a real mission's maps (docs/exploration.md, "Planning time").
#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <lcm/lcm-cpp.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/slam_update_t.hpp>

#include "explorer_node.hpp"
#include "cli/command_line.hpp"
#include "explorer_options.hpp"
#include "map_message.hpp"
#include "plan_report.hpp"
#include "plan_worker.hpp"
#include "planning/cspace.hpp"
#include "planning/driven_trail.hpp"
#include "planning/live_view.hpp"
#include "planning/mission.hpp"
#include "runtime/channels.hpp"
#include "runtime/config.hpp"

namespace {

// --every-map: each MAP planned at the newest pose and scan before it, as the
// explorer's worker plans the map it has (it plans once per replan period, so a
// mission's plans are a subset of these). Greedy plans search the followed
// goal's path too (GoalFocus): the goal of the log's EXPLORE_STATE while it
// is MOVING, or, in a log without it, the goal committed to as the mission
// does (kept while a candidate matches it, else the new plan's best). Not the
// tight fallback nor the blacklist: the blacklist only drops candidates, the
// fallback is a second plan. With --tight every plan is a tight fallback
// instead, along the trail kept from the log's SLAM_UPDATE and poses.
int time_every_map(lcm::LogFile& log, const std::string& log_path, const std::string& map_channel,
                   const std::string& pose_channel, const pex::explorer::ExplorerOptions& options,
                   const pex::planning::PlannerOptions& planner, bool use_cache, const std::string& csv_path,
                   std::int64_t from_utime, bool tight) {
  // As the explorer's worker keeps it: the C-space's offset tiles and the
  // path graph's segment tests between plans.
  pex::planning::PlanCache cache;
  std::optional<pex::pose_t> pose;
  std::optional<pex::laser_scan_t> scan;
  struct Timed {
    double cpu_ms;
    std::int64_t utime;
    std::size_t vertices;
  };
  std::vector<Timed> timed;
  // --tight: every plan is a tight fallback, along the way the robot drove
  // as the explorer keeps it (the endgame's plans, timed alone).
  pex::explorer::TrailKeeper trails;
  std::size_t bad_maps = 0, failed = 0;  // failed: no plan at all (Plan::error), not merely no goal
  std::optional<pex::planning::GoalFocus> focus;
  // FNV-1a over every plan's candidates (positions, reachability, costs and
  // paths, bit for bit) and best: a change of the planner that only makes it
  // faster must leave it as it was.
  // The goals digest covers each plan's chosen goal and its path only: a
  // change that searches more or fewer candidates (their costs, +inf or not)
  // but chooses the same leaves it as it was.
  std::uint64_t digest = 14695981039346656037ull, goals_digest = digest;
  auto mix_into = [](std::uint64_t& into, double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    for (int k = 0; k < 8; ++k) into = (into ^ ((bits >> (8 * k)) & 0xffu)) * 1099511628211ull;
  };
  auto mix = [&](double v) { mix_into(digest, v); };
  bool logged_goals = false;  // EXPLORE_STATE seen: its goal is the focus
  // --plans-csv: one line per plan, what it cost and what it had to do, to
  // see what the slow plans have in common.
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> csv(nullptr, &std::fclose);
  if (!csv_path.empty()) {
    csv.reset(std::fopen(csv_path.c_str(), "w"));
    if (!csv) {
      std::fprintf(stderr, "pex-plan: cannot write %s\n", csv_path.c_str());
      return EX_CANTCREAT;
    }
    std::fprintf(csv.get(), "utime,cpu_ms,map_vertices,cspace_vertices,reflex_nodes,candidates,approach_candidates,"
                            "segment_tests,offset_tiles_computed,graph_tests_new,graph_tests_retested,focus,"
                            "best_path_m,focus_path_m\n");
  }
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
    if (e->channel == pex::runtime::channels::kLidarScan) {
      pex::laser_scan_t s;
      if (s.decode(e->data, 0, e->datalen) >= 0) scan = std::move(s);
    } else if (tight && e->channel == pex::runtime::channels::kSlamUpdate) {
      pex::slam_update_t u;
      if (u.decode(e->data, 0, e->datalen) < 0) continue;
      try {
        trails.on_slam_update(u);
      } catch (const std::invalid_argument&) {
        // refused as the explorer refuses it: the trails stay as they were
      }
    } else if (e->channel == pose_channel) {
      pex::pose_t p;
      if (p.decode(e->data, 0, e->datalen) >= 0) {
        pose = p;
        if (tight && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta))
          trails.on_pose({p.x, p.y, p.theta});
      }
    } else if (e->channel == pex::runtime::channels::kExploreState) {
      pex::explore_state_t state;
      if (state.decode(e->data, 0, e->datalen) < 0) continue;
      logged_goals = true;
      focus.reset();
      if (state.phase == pex::explore_state_t::PHASE_MOVING && state.has_goal) {
        const pex::planning::Point goal(state.goal_x, state.goal_y);
        focus = pex::planning::GoalFocus{goal, goal, options.mission.goal_match_radius_m};
      }
    } else if (e->channel == map_channel && pose) {
      pex::polygon_map_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) {
        ++bad_maps;
        continue;
      }
      if (tight) trails.on_map(m);
      if (m.utime < from_utime) continue;  // the slow end of a mission, timed alone
      const auto decoded = pex::explorer::decode_map(m, options.map);
      if (!decoded.ok) {
        ++bad_maps;
        continue;
      }
      const pex::geometry::Pose2 robot{pose->x, pose->y, pose->theta};
      pex::planning::PlanRequest request;
      request.map = std::make_shared<const pex::planning::TypedMultiPolygon>(decoded.polygons);
      request.pose = robot;
      request.options = planner;
      if (scan) request.live_view = pex::explorer::live_view_of(*scan, robot, options.live_view, request.map.get());
      request.focus = focus;
      request.tight = tight;
      if (tight) request.trail = trails.trail_for_map();
      const auto tiles_before = cache.offsets.counters();
      const auto tests_before = cache.visibility_counters();
      // Timed as the explorer times its worker: the thread's CPU, live view union included.
      const double started = pex::explorer::thread_cpu_ms();
      const auto result = pex::planning::compute_plan(request, use_cache ? &cache : nullptr);
      const double cpu_ms = pex::explorer::thread_cpu_ms() - started;
      if (csv) {
        const auto tiles = cache.offsets.counters();
        const auto tests = cache.visibility_counters();
        const auto& stats = result.plan.stats;
        double focus_path_m = -1.0;
        for (const auto& c : result.plan.candidates)
          if (focus && focus->matches(c) && c.reachable && !c.path.empty()) focus_path_m = c.path_length_m;
        const auto* best = result.plan.best_candidate();
        std::fprintf(csv.get(), "%lld,%.3f,%zu,%d,%d,%zu,%d,%lld,%lld,%lld,%lld,%d,%.2f,%.2f\n",
                     static_cast<long long>(m.utime), cpu_ms, pex::mapping::vertex_count(decoded.polygons),
                     stats.cspace_vertices, stats.reflex_nodes, result.plan.candidates.size(), stats.approach_candidates,
                     static_cast<long long>(stats.segment_tests), static_cast<long long>(tiles.misses - tiles_before.misses),
                     static_cast<long long>(tests.new_pairs - tests_before.new_pairs),
                     static_cast<long long>(tests.retested - tests_before.retested), focus ? 1 : 0,
                     best ? best->path_length_m : -1.0, focus_path_m);
      }
      if (!result.plan.ok) ++failed;
      for (const auto& c : result.plan.candidates) {
        mix(c.position.x());
        mix(c.position.y());
        mix(c.reachable ? 1.0 : 0.0);
        mix(c.cost);
        for (const auto& q : c.path) {
          mix(q.x());
          mix(q.y());
        }
      }
      mix(static_cast<double>(result.plan.best));
      if (const auto* best = result.plan.best_candidate()) {
        mix_into(goals_digest, best->position.x());
        mix_into(goals_digest, best->position.y());
        for (const auto& q : best->path) {
          mix_into(goals_digest, q.x());
          mix_into(goals_digest, q.y());
        }
      } else {
        mix_into(goals_digest, -1.0);
      }
      timed.push_back({cpu_ms, m.utime, pex::mapping::vertex_count(decoded.polygons)});
      if (logged_goals) continue;
      const auto& candidates = result.plan.candidates;
      const bool kept = focus && std::any_of(candidates.begin(), candidates.end(),
                                             [&](const auto& c) { return focus->matches(c) && c.reachable; });
      if (!kept) focus.reset();
      if (const auto* best = result.plan.best_candidate(); best && !kept)
        focus = pex::planning::GoalFocus{best->position, best->frontier_point, options.mission.goal_match_radius_m};
    }
  }
  if (timed.empty()) {
    std::fprintf(stderr, "pex-plan: no %s with a %s before it in %s\n", map_channel.c_str(), pose_channel.c_str(),
                 log_path.c_str());
    return EX_DATAERR;
  }
  std::vector<double> ms;
  std::size_t most_vertices = 0;
  for (const auto& t : timed) {
    ms.push_back(t.cpu_ms);
    most_vertices = std::max(most_vertices, t.vertices);
  }
  std::sort(ms.begin(), ms.end());
  auto quantile = [&](double q) { return ms[static_cast<std::size_t>(q * static_cast<double>(ms.size() - 1))]; };
  std::printf("strategy %s: %zu plans (%zu failed), %zu MAP messages refused; maps up to %zu vertices\n",
              pex::planning::to_string(planner.strategy), timed.size(), failed, bad_maps, most_vertices);
  std::printf("plans digest %016llx, goals digest %016llx (the same log and planner give the same)\n",
              static_cast<unsigned long long>(digest), static_cast<unsigned long long>(goals_digest));
  std::printf("plan CPU ms: p50 %.2f  p90 %.2f  p99 %.2f  max %.2f\n", quantile(0.5), quantile(0.9), quantile(0.99),
              ms.back());
  std::printf("offset tiles: %lld kept from an earlier plan, %lld computed%s\n",
              static_cast<long long>(cache.offsets.counters().hits), static_cast<long long>(cache.offsets.counters().misses),
              use_cache ? "" : " (cache off: --no-cache)");
  std::printf("approach point searches: %lld answered from an earlier plan's tries, %lld searched afresh\n",
              static_cast<long long>(cache.approaches.counters().kept),
              static_cast<long long>(cache.approaches.counters().searched));
  const auto visibility = cache.visibility_counters();
  std::printf("path graph segment tests (%lld graphs built): %lld kept from an earlier plan, %lld tested again near "
              "a change, %lld of new pairs; %lld graphs afresh (most of the boundary changed)\n",
              static_cast<long long>(visibility.builds), static_cast<long long>(visibility.kept),
              static_cast<long long>(visibility.retested), static_cast<long long>(visibility.new_pairs),
              static_cast<long long>(visibility.rebuilt));
  std::sort(timed.begin(), timed.end(), [](const Timed& a, const Timed& b) { return a.cpu_ms > b.cpu_ms; });
  std::printf("slowest (plan one with --utime):\n");
  for (std::size_t i = 0; i < std::min<std::size_t>(5, timed.size()); ++i)
    std::printf("  utime %lld  %.2f ms  %zu vertices\n", static_cast<long long>(timed[i].utime), timed[i].cpu_ms,
                timed[i].vertices);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Run the explorer's planner on a logged MAP and show why it chose what it chose"};
  std::string log_path, config_path, map_channel{pex::runtime::channels::kMap}, pose_channel{"SLAM_POSE"}, svg_path,
      csv_path;
  std::int64_t at_utime = -1, from_utime = 0;
  bool tight = false, every_map = false, no_cache = false, blacklist_from_log = false, request_at_utime = false;
  std::string strategy;
  std::vector<double> focus_xy;
  app.add_option("--log", log_path, "LCM log with MAP and pose messages")->required();
  app.add_option("--config", config_path, "explorer config (planner options); default: the defaults in code");
  app.add_option("--map-channel", map_channel, "channel of the pex.polygon_map_t messages");
  app.add_option("--pose-channel", pose_channel, "channel of the robot's pex.pose_t (SLAM_POSE, SIM_TRUTH)");
  app.add_option("--utime", at_utime, "plan on the last MAP at or before this message utime (default: the last MAP)");
  app.add_flag("--tight", tight,
               "plan without the clearance margin and along the way the robot drove (the explorer's tight fallback); "
               "with --every-map, every plan so");
  app.add_flag("--blacklist-from-log", blacklist_from_log,
               "blacklist the goals the log's last EXPLORE_STATE up to the map lists as visited or given up (the "
               "mission's blacklist, as far as it shows it)");
  app.add_option("--svg", svg_path, "draw map, C-space, candidates and the chosen path");
  app.add_flag("--every-map", every_map, "plan on every MAP of the log and print the plan CPU time percentiles");
  app.add_option("--plans-csv", csv_path, "with --every-map: one CSV line per plan (its CPU, map size, candidates, "
                 "segment tests, offset tiles computed, path lengths)");
  app.add_option("--from-utime", from_utime,
                 "with --every-map: plan only on the maps of this message utime and later (a mission's slow end; the "
                 "caches start empty there)");
  app.add_flag("--no-cache,--no-offset-cache", no_cache,
               "with --every-map: compute every offset tile and every segment test of the path graph afresh (the "
               "plans must not change)");
  app.add_option("--strategy", strategy, "goal strategy (greedy | tour); default: the config's")
      ->check(CLI::IsMember({"greedy", "tour"}));
  app.add_flag("--request-at-utime", request_at_utime,
               "with --utime: the robot's pose, the live view's scan and the blacklist as they were at --utime (a plan "
               "the explorer requested then), not as they were when the map came");
  app.add_option("--focus", focus_xy,
                 "plan as while following a goal: GOAL_X GOAL_Y FRONTIER_X FRONTIER_Y (m, map frame; EXPLORE_STATE's "
                 "goal and the frontier it looks at), matched within the config's goal_match_radius_m")
      ->expected(4);
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
  if (!strategy.empty())
    planner.strategy = *pex::planning::parse_goal_strategy(strategy);

  lcm::LogFile log(log_path, "r");
  if (!log.good()) {
    std::fprintf(stderr, "pex-plan: cannot read %s\n", log_path.c_str());
    return EX_NOINPUT;
  }
  if (every_map)
    return time_every_map(log, log_path, map_channel, pose_channel, options, planner, !no_cache, csv_path, from_utime,
                          tight);
  std::optional<pex::polygon_map_t> map;
  std::optional<pex::pose_t> pose;           // newest pose up to the chosen map
  std::optional<pex::pose_t> pose_pending;   // newest pose overall, taken with the next map
  std::optional<pex::laser_scan_t> scan, scan_pending;  // the same for LIDAR_SCAN (the live view)
  std::vector<pex::geometry::Point> blacklist, blacklist_pending;  // --blacklist-from-log
  // The way the robot drove, as the explorer keeps it (a tight plan goes along it).
  pex::explorer::TrailKeeper trails;
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
    if (e->channel == pex::runtime::channels::kSlamUpdate) {
      pex::slam_update_t u;
      if (u.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && u.utime > at_utime) continue;
      try {
        trails.on_slam_update(u);
      } catch (const std::invalid_argument&) {
        // refused as the explorer refuses it: the trails stay as they were
      }
    } else if (blacklist_from_log && e->channel == pex::runtime::channels::kExploreState) {
      pex::explore_state_t st;
      if (st.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && st.utime > at_utime) continue;
      blacklist_pending = pex::plan_tool::blacklist_of(st);
    } else if (e->channel == pex::runtime::channels::kLidarScan) {
      pex::laser_scan_t s;
      if (s.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && s.utime > at_utime) continue;
      scan_pending = std::move(s);
    } else if (e->channel == pose_channel) {
      pex::pose_t p;
      if (p.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && p.utime > at_utime) continue;
      pose_pending = p;
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta)) trails.on_pose({p.x, p.y, p.theta});
    } else if (e->channel == map_channel) {
      pex::polygon_map_t m;
      if (m.decode(e->data, 0, e->datalen) < 0) continue;
      if (at_utime >= 0 && m.utime > at_utime) continue;
      map = std::move(m);
      pose = pose_pending;
      scan = scan_pending;
      blacklist = blacklist_pending;
    }
  }
  if (request_at_utime && map) {
    pose = pose_pending;
    scan = scan_pending;
    blacklist = blacklist_pending;
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
  const auto live = scan ? pex::explorer::live_view_of(*scan, robot, options.live_view, &decoded.polygons) : nullptr;
  const auto planned_on = live ? pex::planning::with_live_view(decoded.polygons, *live) : decoded.polygons;
  // A tight plan also goes along the way the robot drove (trail_corridor_m).
  trails.on_map(*map);
  const auto trail = tight ? trails.trail_for_map() : nullptr;
  pex::planning::DrivenWay way;
  if (trail) way = {*trail, planner.trail_corridor_m};
  const auto* driven = way.points.empty() ? nullptr : &way;
  const double plan_started_ms = pex::explorer::thread_cpu_ms();
  std::optional<pex::planning::GoalFocus> focus;
  if (focus_xy.size() == 4)
    focus = pex::planning::GoalFocus{{focus_xy[0], focus_xy[1]}, {focus_xy[2], focus_xy[3]},
                                     options.mission.goal_match_radius_m};
  const auto plan = pex::planning::plan_exploration(decoded.polygons, robot, blacklist, planner, live ? &planned_on : nullptr,
                                                    focus ? &*focus : nullptr, nullptr, driven);
  const double plan_cpu_ms = pex::explorer::thread_cpu_ms() - plan_started_ms;
  pex::planning::ConfigurationSpace cspace;
  cspace.build(planned_on, planner.cspace, nullptr, driven);
  std::printf("live view: %s\n", live ? "united into the map (newest LIDAR_SCAN)"
                                      : (scan ? "off (live_view_range_m = 0)" : "none (no LIDAR_SCAN)"));
  std::printf("plan: %.1f ms CPU (no cache, as a first plan)\n", plan_cpu_ms);
  if (blacklist_from_log) std::printf("blacklist: %zu goals visited or given up (EXPLORE_STATE)\n", blacklist.size());
  if (tight)
    std::printf("trail: %s\n", !trail ? "none for the map's particle and generation"
                                       : (std::to_string(trail->size()) + " points, corridor " +
                                          std::to_string(planner.trail_corridor_m) + " m either side")
                                             .c_str());
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
