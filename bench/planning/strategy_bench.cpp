// pex-bench-strategies: the goal strategies side by side on every world,
// without the daemons and without SLAM: the robot follows each plan's path
// exactly (bench/planning/mission_maps.hpp, replanning on the way and leaving
// a goal whose frontier it has seen, as the explorer's mission does), with the
// explorer's planner options from its config. One JSON line per world and
// strategy (path driven, and the final map's coverage of the floor a 0.25 m
// disk can sweep from START, as pex-explore-report scores MAP_FREE), then the
// path summed per strategy over the worlds both finished.
// Deterministic (fixed seeds, true poses): a strategy change can be judged on
// every world in minutes, before the exploration benchmark (scripts/bench.sh
// explore) runs the whole set with SLAM for the figures of record.
//
//   pex-bench-strategies [--config config/explorer.toml] [--strategies greedy,tour] [WORLD.wkt...]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <boost/geometry/io/wkt/write.hpp>

#include "evaluation/exploration_metrics.hpp"
#include "explorer_options.hpp"
#include "latency_stats.hpp"
#include "mapper.hpp"
#include "mission_maps.hpp"
#include "plan_worker.hpp"
#include "runtime/config.hpp"

namespace {

using pex::mapping::Point;
using pex::mapping::TypedMultiPolygon;
using pex::planning::GoalStrategy;
using pex::planning::Plan;
using pex::planning::PlannerOptions;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The goal strategies side by side on every world (true poses, no daemons): one JSON line each"};
  std::string config_path = std::string(PEX_SOURCE_DIR) + "/config/explorer.toml";
  std::string mapper_config_path = std::string(PEX_SOURCE_DIR) + "/config/polygon_mapper.toml";
  std::vector<std::string> strategies;
  std::vector<std::string> worlds;
  double max_travel_m = 4000.0;
  std::string map_wkt_dir, trace_dir;
  app.add_option("--config", config_path, "explorer config (planner options)")->check(CLI::ExistingFile);
  app.add_option("--mapper-config", mapper_config_path, "polygon_mapper config (scan polygons, map)")
      ->check(CLI::ExistingFile);
  // One word, comma-separated: a list option would take the world files
  // after it for strategy names, and fail only after the first whole run.
  std::string strategy_list = "greedy,tour";
  app.add_option("--strategies", strategy_list, "goal strategies to compare, comma-separated (greedy,tour)");
  app.add_option("--max-travel-m", max_travel_m, "give a mission up after this much driving")->check(CLI::PositiveNumber);
  app.add_option("--map-wkt-dir", map_wkt_dir,
                 "write each run's final map (MAP_FREE) there as WORLD-STRATEGY.wkt, one POLYGON per line (world frame)")
      ->check(CLI::ExistingDirectory);
  bool carry_goal = false;
  app.add_flag("--carry-goal", carry_goal,
               "the plans on the way carry the goal followed, as the explorer's follow plans do (MissionMapsOptions::"
               "carry_goal; off: they choose anew)");
  app.add_option("--trace-dir", trace_dir,
                 "write each run's plans there as WORLD-STRATEGY.csv: travel so far (m, the poses' straight legs), "
                 "the planning map's area (m2), candidates, the plan's best candidate: its place, path length, frontier point, "
                 "frontier chain's length, the unknown area behind that chain when enclosed or in a bay (inf: open) and "
                 "whether it is an approach point (plan by plan)")
      ->check(CLI::ExistingDirectory);
  std::string dump_at_list;  // one word, comma-separated, as --strategies
  app.add_option("--dump-at", dump_at_list,
                 "with --trace-dir: at the first plan at or after each of these travels (m, comma-separated), write "
                 "its planning map's edges (piece, ring: 0 outer, k hole k; x1, y1, x2, y2, type) and its candidates as "
                 "WORLD-STRATEGY-at-M-{edges,candidates}.csv");
  app.add_option("worlds", worlds, "world files (default: every worlds/*.wkt)")->check(CLI::ExistingFile);
  app.set_version_flag("--version", std::string("pex-bench-strategies ") + PEX_VERSION);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 64;
  }
  for (std::size_t from = 0; from <= strategy_list.size();) {
    const std::size_t comma = std::min(strategy_list.find(',', from), strategy_list.size());
    strategies.push_back(strategy_list.substr(from, comma - from));
    if (!pex::planning::parse_goal_strategy(strategies.back())) {
      std::fprintf(stderr, "pex-bench-strategies: unknown strategy '%s' (greedy, tour)\n", strategies.back().c_str());
      return 64;
    }
    from = comma + 1;
  }
  std::vector<double> dump_at_m;
  for (std::size_t from = 0; from < dump_at_list.size();) {
    const std::size_t comma = std::min(dump_at_list.find(',', from), dump_at_list.size());
    try {
      dump_at_m.push_back(std::stod(dump_at_list.substr(from, comma - from)));
    } catch (const std::exception&) {
      std::fprintf(stderr, "pex-bench-strategies: --dump-at: '%s' is no travel in m\n",
                   dump_at_list.substr(from, comma - from).c_str());
      return 64;
    }
    from = comma + 1;
  }
  if (!dump_at_m.empty() && trace_dir.empty()) {
    std::fprintf(stderr, "pex-bench-strategies: --dump-at writes into --trace-dir: give both\n");
    return 64;
  }
  if (worlds.empty()) {
    for (const auto& entry : std::filesystem::directory_iterator(std::string(PEX_SOURCE_DIR) + "/worlds"))
      if (entry.path().extension() == ".wkt") worlds.push_back(entry.path().string());
    std::sort(worlds.begin(), worlds.end());
  }
  pex::explorer::ExplorerOptions explorer;
  pex::polygon_mapper::MapperOptions mapper;
  try {
    auto config = pex::runtime::ConfigReader::from_file(config_path);
    explorer = pex::explorer::load_options(config);
    auto mapper_config = pex::runtime::ConfigReader::from_file(mapper_config_path);
    mapper = pex::polygon_mapper::load_options(mapper_config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pex-bench-strategies: %s\n", e.what());
    return 78;
  }
  std::map<std::string, std::map<std::string, double>> path_of;  // world -> strategy -> m
  for (const auto& world : worlds) {
    const std::string name = std::filesystem::path(world).stem().string();
    std::string error;
    const auto sim_world = pex::bench::read_world(world, error);
    if (!sim_world) {
      std::fprintf(stderr, "pex-bench-strategies: %s\n", error.c_str());
      return 65;
    }
    // The floor the simulator's robot (a 0.25 m disk) can sweep, to score the maps against.
    constexpr double kSimRobotRadiusM = 0.25, kWallToleranceM = 0.1;
    const auto reachable = pex::evaluation::reachable_free_space(*sim_world, kSimRobotRadiusM, sim_world->start);
    const pex::evaluation::WallIndex walls(sim_world->walls);
    for (const auto& strategy_name : strategies) {
      const auto strategy = pex::planning::parse_goal_strategy(strategy_name);
      if (!strategy) {
        std::fprintf(stderr, "pex-bench-strategies: unknown strategy '%s'\n", strategy_name.c_str());
        return 64;
      }
      PlannerOptions options = explorer.mission.planner;
      options.strategy = *strategy;
      PlannerOptions tight = options;
      tight.cspace.clearance_margin_m = 0.0;
      // The way in's margin, as Mission::way_in_margin_m gives it.
      PlannerOptions way_in = options;
      way_in.cspace.clearance_margin_m =
          std::min(explorer.mission.way_in_margin_m, options.cspace.clearance_margin_m);
      pex::bench::MissionMapsOptions mission;
      mission.max_goals = 100000;
      mission.max_travel_m = max_travel_m;
      mission.replan_step_m = 0.4;  // 0.4 m/s, a plan a second
      mission.replan_on_the_way = true;
      mission.goal_match_radius_m = explorer.mission.goal_match_radius_m;
      mission.carry_goal = carry_goal;
      mission.back_out_m = explorer.mission.back_out_m;
      mission.robot_radius_m = kSimRobotRadiusM;  // stopped short of what the map does not hold, as the guard stops
      mission.keep_snapshots = false;
      mission.scan = mapper.scan;
      mission.map = mapper.map;
      const bool fallback = explorer.mission.tight_fallback;
      // Each plan's CPU time, with what the planner reuses kept from plan to
      // plan as the explorer's planning thread keeps it (one cache per margin).
      pex::explorer::LatencyStats plan_cpu_ms;
      pex::planning::PlanCache offsets, tight_offsets, way_in_offsets;
      auto timed_plan = [&](const TypedMultiPolygon& map, const pex::geometry::Pose2& pose,
                            const std::vector<Point>& blacklist, const PlannerOptions& o,
                            pex::planning::PlanCache& cache, const pex::planning::GoalFocus* focus) {
        const double started = pex::explorer::thread_cpu_ms();
        Plan plan = pex::planning::plan_exploration(map, pose, blacklist, o, nullptr, focus, &cache);
        plan_cpu_ms.add(pex::explorer::thread_cpu_ms() - started);
        return plan;
      };
      // The plans' trace (--trace-dir) and the travel at which the map
      // first held 99 % of its final area (how long the endgame was).
      struct TracePoint {
        double travel_m, map_m2;
      };
      std::vector<TracePoint> trace;
      std::string trace_lines;
      std::set<double> dumped;  // --dump-at travels written
      std::optional<pex::geometry::Pose2> last_pose;
      double travel_m = 0.0;
      auto traced = [&](const TypedMultiPolygon& map, const pex::geometry::Pose2& pose, const Plan& plan) {
        if (last_pose) travel_m += std::hypot(pose.x_m - last_pose->x_m, pose.y_m - last_pose->y_m);
        last_pose = pose;
        double area_m2 = 0.0;
        for (const auto& piece : map) area_m2 += boost::geometry::area(piece.geometry);
        trace.push_back({travel_m, area_m2});
        if (trace_dir.empty()) return;
        const auto* goal = plan.best_candidate();
        char line[384];
        std::snprintf(line, sizeof line, "%.3f,%.3f,%zu,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%d\n", travel_m, area_m2,
                      plan.candidates.size(), goal ? goal->position.x() : NAN, goal ? goal->position.y() : NAN,
                      goal ? goal->path_length_m : NAN, goal ? goal->frontier_point.x() : NAN,
                      goal ? goal->frontier_point.y() : NAN, goal ? goal->chain_length_m : NAN,
                      goal ? goal->enclosed_area_m2 : NAN, goal ? static_cast<int>(goal->approach) : -1);
        trace_lines += line;
        for (const double at_m : dump_at_m) {
          if (travel_m < at_m || dumped.count(at_m)) continue;
          dumped.insert(at_m);
          char stem[96];
          std::snprintf(stem, sizeof stem, "%s-%s-at-%g", name.c_str(), strategy_name.c_str(), at_m);
          std::ofstream edges(std::filesystem::path(trace_dir) / (std::string(stem) + "-edges.csv"));
          edges.precision(17);  // the map as planned on, to read back
          edges << "piece,ring,x1,y1,x2,y2,type\n";
          for (std::size_t piece_id = 0; piece_id < map.size(); ++piece_id) {
            const auto& piece = map[piece_id];
            std::size_t ring_id = 0;
            auto write_ring = [&](const pex::mapping::Ring& ring, const std::vector<pex::mapping::EdgeType>& types) {
              for (std::size_t i = 0; i + 1 < ring.size() && i < types.size(); ++i)
                edges << piece_id << ',' << ring_id << ',' << ring[i].x() << ',' << ring[i].y() << ',' << ring[i + 1].x() << ','
                      << ring[i + 1].y() << ',' << pex::mapping::to_string(types[i]) << '\n';
              ++ring_id;
            };
            write_ring(piece.geometry.outer(), piece.edge_types[0]);
            for (std::size_t k = 0; k < piece.geometry.inners().size(); ++k)
              write_ring(piece.geometry.inners()[k], piece.edge_types[1 + k]);
          }
          std::ofstream candidates(std::filesystem::path(trace_dir) / (std::string(stem) + "-candidates.csv"));
          candidates << "x,y,frontier_x,frontier_y,chain,chain_m,unknown_behind_m2,approach,reachable,blacklisted,"
                        "path_m,best\n";
          for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
            const auto& c = plan.candidates[i];
            candidates << c.position.x() << ',' << c.position.y() << ',' << c.frontier_point.x() << ','
                       << c.frontier_point.y() << ',' << c.chain << ',' << c.chain_length_m << ','
                       << c.enclosed_area_m2 << ',' << c.approach << ',' << c.reachable << ',' << c.blacklisted << ','
                       << c.path_length_m << ',' << (static_cast<int>(i) == plan.best) << '\n';
          }
          candidates << "# robot," << pose.x_m << ',' << pose.y_m << ',' << pose.theta_rad << '\n';
        }
      };
      // A way in after an approach point, as the mission looks for one when
      // it may plan without the full margin (Mission::may_plan_tight).
      pex::bench::MissionPlanner way_in_planner;
      if (fallback && options.cspace.clearance_margin_m > 0.0)
        way_in_planner = [&](const TypedMultiPolygon& map, const pex::geometry::Pose2& pose,
                             const std::vector<Point>& blacklist, const pex::planning::GoalFocus* focus) {
          Plan plan = timed_plan(map, pose, blacklist, way_in, way_in_offsets, focus);
          traced(map, pose, plan);
          return plan;
        };
      const auto maps = pex::bench::emulate_mission(
          *sim_world, mission,
          [&](const TypedMultiPolygon& map, const pex::geometry::Pose2& pose, const std::vector<Point>& blacklist,
              const pex::planning::GoalFocus* focus) {
            Plan plan = timed_plan(map, pose, blacklist, options, offsets, focus);
            // As the mission does (Mission::on_plan, on_select_plan): without the
            // margin only when nothing is reachable and the margin may be why.
            if (!plan.best_candidate() && fallback && pex::planning::margin_may_block(plan))
              plan = timed_plan(map, pose, blacklist, tight, tight_offsets, focus);
            traced(map, pose, plan);
            return plan;
          },
          way_in_planner);
      double travel_at_99_m = 0.0;
      if (!trace.empty()) {
        const double final_m2 = trace.back().map_m2;
        for (const auto& t : trace)
          if (t.map_m2 >= 0.99 * final_m2) {
            travel_at_99_m = t.travel_m;
            break;
          }
      }
      if (!trace_dir.empty()) {
        const auto out_path = std::filesystem::path(trace_dir) / (name + "-" + strategy_name + ".csv");
        std::ofstream out(out_path);
        out << "travel_m,map_m2,candidates,best_x,best_y,best_path_m,best_frontier_x,best_frontier_y,best_chain_m,"
               "best_unknown_behind_m2,best_approach\n"
            << trace_lines;
        if (!out) {
          std::fprintf(stderr, "pex-bench-strategies: cannot write %s\n", out_path.c_str());
          return 73;
        }
      }
      if (!maps.error.empty()) {
        std::fprintf(stderr, "pex-bench-strategies: %s: %s\n", name.c_str(), maps.error.c_str());
        return 70;
      }
      if (maps.done) path_of[name][strategy_name] = maps.travelled_m;
      if (!map_wkt_dir.empty()) {
        const auto out_path = std::filesystem::path(map_wkt_dir) / (name + "-" + strategy_name + ".wkt");
        std::ofstream out(out_path);
        for (const auto& piece : maps.free_space) out << boost::geometry::wkt(piece.geometry) << '\n';
        if (!out) {
          std::fprintf(stderr, "pex-bench-strategies: cannot write %s\n", out_path.c_str());
          return 73;
        }
      }
      // Poses are the world's (the emulated robot starts at START in world coordinates).
      const auto score = pex::evaluation::score_map(maps.free_space, pex::geometry::Pose2{0.0, 0.0, 0.0}, reachable,
                                                    walls, kWallToleranceM);
      std::printf(
          "{\"world\":\"%s\",\"strategy\":\"%s\",\"done\":%s,\"path_m\":%.3f,\"goals\":%d,\"goals_seen\":%d,\"backs_out\":%d,\"ways_in\":%d,"
          "\"guard_stops\":%d,\"plans\":%d,\"coverage\":%.5f,\"iou\":%.5f,\"plan_cpu_ms_p50\":%.3f,\"plan_cpu_ms_p99\":%.3f,"
          "\"travel_at_99pct_map_m\":%.1f}\n",
          name.c_str(), strategy_name.c_str(), maps.done ? "true" : "false", maps.travelled_m, maps.goals,
          maps.goals_seen, maps.backs_out, maps.ways_in, maps.guard_stops, maps.plans, score.coverage, score.iou, plan_cpu_ms.quantile(0.5),
          plan_cpu_ms.quantile(0.99), travel_at_99_m);
      std::fflush(stdout);
    }
  }
  // The path summed over the worlds every strategy finished, against the first strategy's.
  std::map<std::string, double> sum;
  int finished = 0;
  for (const auto& [world, by_strategy] : path_of) {
    if (by_strategy.size() != strategies.size()) continue;
    ++finished;
    for (const auto& [s, m] : by_strategy) sum[s] += m;
  }
  std::printf("# summed over %d worlds every strategy finished:", finished);
  for (const auto& s : strategies)
    std::printf(" %s %.1f m (%.3f of %s);", s.c_str(), sum[s], sum[strategies.front()] > 0 ? sum[s] / sum[strategies.front()] : 0.0,
                strategies.front().c_str());
  std::printf("\n");
  return 0;
}
