// pex-bench-planning: what goal selection by a tour costs per plan (issue
// 10): the C-space, the greedy strategy's one search (shortest_paths from the
// robot; and the robot's row alone over the path matrix's sparse graph), the
// path matrix over all candidates (shortest_path_matrix) and the tour on it
// (solve_open_tour), for 10, 30 and 60 candidates, on two maps:
//   campus: a synthetic 160 x 160 m campus, the buildings of
//           worlds/campus.wkt and 40 round trees (16-gons of 0.5 m radius),
//           everything known (the largest map a campus run plans on);
//   intel:  the planning map the mapper builds from the Intel lab log's
//           scans (raw odometry; real, noisy walls and frontiers), grown to
//           about 5000 vertices.
// Candidates are the map's own frontier candidates (intel; as the planner
// makes them) in the robot's piece of the C-space and, where there are fewer
// than asked for, random interior points of that piece (fixed seed); the
// robot is at the first scan pose (intel) or the campus start.
// And whole plans (plan_exploration, both strategies), what the explorer's
// worker runs every replan period, on the maps of emulated missions
// (mission_maps.hpp) in worlds/campus.wkt and worlds/intel.wkt: BM_Plan on
// the mission's largest map, BM_PlanMission on every map of the mission
// (per-plan p50 / p99 / max). Figures are reported (docs/), never asserted;
// CPU time, since the machine is shared. The last stdout line is one JSON
// object.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "median_collector.hpp"
#include "evaluation/carmen_log.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"
#include "mission_maps.hpp"
#include "planning/cspace.hpp"
#include "planning/exploration_planner.hpp"
#include "planning/frontier_goals.hpp"
#include "planning/goal_tour.hpp"
#include "planning/keep_out.hpp"
#include "planning/live_view.hpp"
#include "planning/mission.hpp"
#include "planning/path_matrix.hpp"
#include "planning/scan_guard.hpp"
#include "planning/test_maps.hpp"
#include "planning/visibility_graph.hpp"

namespace {

using namespace pex::planning;
using pex::mapping::Point;
using pex::mapping::TypedMultiPolygon;

constexpr std::size_t kMaxCandidates = 60;

// The planner's defaults as config/explorer.toml sets them.
CSpaceOptions cspace_options() {
  CSpaceOptions o;
  o.robot_radius_m = 0.27;
  o.clearance_margin_m = 0.05;
  o.points_per_circle = 16;
  o.simplify_epsilon_m = 0.01;
  return o;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

struct Scene {
  std::string name;
  TypedMultiPolygon map;
  std::unique_ptr<ConfigurationSpace> cspace;
  Point start;
  std::vector<Point> candidates;  // kMaxCandidates; the first `frontier_candidates` from frontiers
  int frontier_candidates = 0;
  std::size_t map_vertices = 0;
  std::string error;
};

// The scene's map and its C-space; false (the reason in scene.error) when
// the C-space does not build.
bool set_map(Scene& scene, TypedMultiPolygon map) {
  scene.map = std::move(map);
  scene.map_vertices = pex::mapping::vertex_count(scene.map);
  scene.cspace = std::make_unique<ConfigurationSpace>();
  const auto built = scene.cspace->build(scene.map, cspace_options());
  if (!built.ok) scene.error = built.error;
  return built.ok;
}

// Candidates: those of `given` in the robot's piece of the C-space first
// (in order), then random interior points of that piece until there are
// kMaxCandidates: every candidate is reachable.
void fill_candidates(Scene& scene, const std::vector<Point>& given) {
  const pex::mapping::Polygon* piece = nullptr;
  for (const auto& p : scene.cspace->polygons())
    if (boost::geometry::covered_by(scene.start, p.geometry)) piece = &p.geometry;
  if (!piece) return;
  scene.candidates.clear();
  for (const auto& p : given)
    if (scene.candidates.size() < kMaxCandidates && boost::geometry::covered_by(p, *piece)) scene.candidates.push_back(p);
  scene.frontier_candidates = static_cast<int>(scene.candidates.size());
  const auto box = boost::geometry::return_envelope<pex::mapping::Box>(*piece);
  std::mt19937_64 rng(7);
  for (int attempt = 0; attempt < 100000 && scene.candidates.size() < kMaxCandidates; ++attempt) {
    const Point p(uniform(rng, box.min_corner().x(), box.max_corner().x()),
                  uniform(rng, box.min_corner().y(), box.max_corner().y()));
    if (!boost::geometry::covered_by(p, *piece)) continue;
    if (const auto inside = scene.cspace->nearest_interior_point(p, 0.0)) scene.candidates.push_back(*inside);
  }
}

std::unique_ptr<Scene> build_campus() {
  using pex::planning::testing::RingSpec;
  auto scene = std::make_unique<Scene>();
  scene->name = "campus";
  // The buildings of worlds/campus.wkt (holes, clockwise); the courtyard
  // building as its outline, the L-shaped one as an L.
  const double buildings[][4] = {{20, 20, 50, 35},    {70, 15, 95, 45},    {115, 20, 145, 30}, {20, 60, 35, 100},
                                 {55, 65, 100, 80},   {120, 55, 140, 95},  {25, 120, 60, 140}, {75, 105, 90, 145},
                                 {110, 120, 150, 135}, {100, 100, 110, 110}};
  std::vector<RingSpec> holes;
  std::vector<pex::mapping::Box> taken;
  for (const auto& b : buildings) {
    holes.push_back(testing::rectangle_hole(b[0], b[1], b[2], b[3]));
    taken.emplace_back(Point(b[0], b[1]), Point(b[2], b[3]));
  }
  holes.push_back(RingSpec{{Point(55, 90), Point(55, 100), Point(60, 100), Point(60, 95), Point(70, 95), Point(70, 90)}, {}});
  taken.emplace_back(Point(55, 90), Point(70, 100));
  // 40 trees, 0.5 m radius, at least 2 m from buildings, fence and each other.
  std::mt19937_64 rng(2019);
  int trees = 0;
  for (int attempt = 0; attempt < 10000 && trees < 40; ++attempt) {
    const double cx = uniform(rng, 3, 157), cy = uniform(rng, 3, 157);
    const pex::mapping::Box reach(Point(cx - 2.5, cy - 2.5), Point(cx + 2.5, cy + 2.5));
    bool apart = true;
    for (const auto& t : taken) apart = apart && !boost::geometry::intersects(reach, t);
    if (!apart) continue;
    taken.emplace_back(Point(cx - 0.5, cy - 0.5), Point(cx + 0.5, cy + 0.5));
    RingSpec tree;
    for (int k = 0; k < 16; ++k) {
      const double a = -2.0 * M_PI * k / 16;
      tree.points.emplace_back(cx + 0.5 * std::cos(a), cy + 0.5 * std::sin(a));
    }
    holes.push_back(tree);
    ++trees;
  }
  if (!set_map(*scene, {testing::typed_polygon(testing::rectangle(0, 0, 160, 160), holes)})) return scene;
  scene->start = Point(8.0, 8.0);  // the campus world's START
  fill_candidates(*scene, {});
  return scene;
}

// The Intel lab log inserted as bench_mapping does (a scan after 0.2 m or
// 0.25 rad of motion) until the planning map has about `target_vertices`.
std::unique_ptr<Scene> build_intel(std::size_t target_vertices) {
  auto scene = std::make_unique<Scene>();
  scene->name = "intel";
  std::ifstream in(std::string(PEX_SHARED_DIR) + "/data/intel.clf");
  if (!in) {
    scene->error = "no " + std::string(PEX_SHARED_DIR) + "/data/intel.clf";
    return scene;
  }
  const auto log = pex::evaluation::parse_carmen_log(in);
  pex::mapping::PolygonMap map;
  const pex::mapping::ScanPolygonOptions options;
  std::optional<pex::geometry::Pose2> first, last;
  for (const auto& laser : log.lasers) {
    const pex::geometry::Pose2& pose = laser.laser_pose;
    if (last && std::hypot(pose.x_m - last->x_m, pose.y_m - last->y_m) < 0.2 &&
        std::abs(pex::geometry::wrap_angle(pose.theta_rad - last->theta_rad)) < 0.25)
      continue;
    last = pose;
    if (!first) first = pose;
    std::vector<float> ranges = laser.ranges_m;
    for (auto& r : ranges)
      if (r >= laser.max_range_m) r = std::numeric_limits<float>::infinity();
    auto scan = pex::mapping::scan_to_polygon(ranges, laser.angle_min_rad, laser.angle_increment_rad, pose, options);
    if (scan.ok) map.insert(scan.polygon);
    if (map.planning_vertex_count() >= target_vertices) break;
  }
  auto merged = map.planning_map();
  if (!merged.ok || !first) {
    scene->error = "the Intel planning map failed: " + merged.error;
    return scene;
  }
  if (!set_map(*scene, std::move(merged.polygons))) return scene;
  const auto start = scene->cspace->nearest_interior_point(Point(first->x_m, first->y_m), 0.5);
  if (!start) {
    scene->error = "the first Intel pose is not in the C-space";
    return scene;
  }
  scene->start = *start;
  // The planner's candidates: on the frontiers, moved into the C-space.
  FrontierGoalOptions frontier;
  frontier.sensor_range_m = 4.0;
  frontier.min_frontier_length_m = 0.4;
  std::vector<Point> given;
  for (const auto& fp : frontier_candidates(frontier_chains(scene->map), frontier))
    if (const auto inside = scene->cspace->nearest_interior_point(fp.point, 1.0)) given.push_back(*inside);
  fill_candidates(*scene, given);
  return scene;
}

Scene& scene(int which) {
  static std::map<int, std::unique_ptr<Scene>> cache;
  auto& slot = cache[which];
  if (!slot) slot = which == 0 ? build_campus() : build_intel(5000);
  return *slot;
}

std::vector<Point> candidates(const Scene& s, std::size_t n) {
  return {s.candidates.begin(), s.candidates.begin() + static_cast<std::ptrdiff_t>(std::min(n, s.candidates.size()))};
}

bool usable(benchmark::State& state, const Scene& s) {
  if (!s.error.empty() || s.candidates.size() < kMaxCandidates) {
    state.SkipWithError((s.name + ": " + (s.error.empty() ? "too few candidates" : s.error)).c_str());
    return false;
  }
  state.SetLabel(s.name);
  return true;
}

void map_counters(benchmark::State& state, const Scene& s) {
  state.counters["map_vertices"] = static_cast<double>(s.map_vertices);
  state.counters["reflex"] = static_cast<double>(s.cspace->reflex_nodes().size());
  state.counters["frontier_cands"] = s.frontier_candidates;
}

void BM_CSpace(benchmark::State& state) {
  Scene& s = scene(static_cast<int>(state.range(0)));
  if (!usable(state, s)) return;
  for (auto _ : state) {
    ConfigurationSpace cs;
    benchmark::DoNotOptimize(cs.build(s.map, cspace_options()));
  }
  map_counters(state, s);
}

// The greedy strategy's search: one lazy Dijkstra from the robot.
void BM_ShortestPaths(benchmark::State& state) {
  Scene& s = scene(static_cast<int>(state.range(0)));
  if (!usable(state, s)) return;
  const auto targets = candidates(s, static_cast<std::size_t>(state.range(1)));
  std::int64_t tests = 0;
  for (auto _ : state) {
    auto sp = shortest_paths(*s.cspace, s.start, targets);
    tests = sp.segment_tests;
    benchmark::DoNotOptimize(sp);
  }
  map_counters(state, s);
  state.counters["segment_tests"] = static_cast<double>(tests);
}

// The same sparse graph, the robot's row only: what the greedy strategy
// could use instead of shortest_paths.
void BM_StartRow(benchmark::State& state) {
  Scene& s = scene(static_cast<int>(state.range(0)));
  if (!usable(state, s)) return;
  const auto targets = candidates(s, static_cast<std::size_t>(state.range(1)));
  PathMatrix m;
  for (auto _ : state) {
    m = shortest_path_matrix(*s.cspace, s.start, targets, PathMatrixOptions{.between_targets = false});
    benchmark::DoNotOptimize(m);
  }
  map_counters(state, s);
  state.counters["segment_tests"] = static_cast<double>(m.segment_tests);
}

void BM_PathMatrix(benchmark::State& state) {
  Scene& s = scene(static_cast<int>(state.range(0)));
  if (!usable(state, s)) return;
  const auto targets = candidates(s, static_cast<std::size_t>(state.range(1)));
  PathMatrix m;
  for (auto _ : state) {
    m = shortest_path_matrix(*s.cspace, s.start, targets);
    benchmark::DoNotOptimize(m);
  }
  map_counters(state, s);
  state.counters["graph_edges"] = static_cast<double>(m.graph_edges);
  state.counters["segment_tests"] = static_cast<double>(m.segment_tests);
  int reachable = 0;
  for (const double d : m.from_start_m) reachable += std::isfinite(d) ? 1 : 0;
  state.counters["reachable"] = reachable;
}

void BM_Tour(benchmark::State& state) {
  Scene& s = scene(static_cast<int>(state.range(0)));
  if (!usable(state, s)) return;
  const auto m = shortest_path_matrix(*s.cspace, s.start, candidates(s, static_cast<std::size_t>(state.range(1))));
  OpenTour tour;
  for (auto _ : state) {
    tour = solve_open_tour(m);
    benchmark::DoNotOptimize(tour);
  }
  const auto greedy = nearest_neighbour_tour(m.from_start_m, m.between_m);
  state.counters["tour_over_greedy"] = greedy.length_m > 0 ? tour.length_m / greedy.length_m : 1.0;
  state.counters["moves"] = tour.improving_moves;
}

// What a tour plan adds up to without the frontier extraction: C-space,
// matrix, tour.
void BM_PlanTour(benchmark::State& state) {
  Scene& s = scene(static_cast<int>(state.range(0)));
  if (!usable(state, s)) return;
  const auto targets = candidates(s, static_cast<std::size_t>(state.range(1)));
  for (auto _ : state) {
    ConfigurationSpace cs;
    cs.build(s.map, cspace_options());
    const auto m = shortest_path_matrix(cs, s.start, targets);
    benchmark::DoNotOptimize(solve_open_tour(m));
  }
  map_counters(state, s);
}

// The explorer's planner options (config/explorer.toml).
PlannerOptions planner_options(GoalStrategy strategy) {
  PlannerOptions o;
  o.strategy = strategy;
  o.cspace = cspace_options();
  o.frontier.sensor_range_m = 4.0;
  o.frontier.min_frontier_length_m = 0.4;
  return o;
}

// Whole missions' maps (mission_maps.hpp) on worlds/campus.wkt and
// worlds/intel.wkt, the robot following the greedy planner's paths: the
// maps of every size a mission plans on, with their frontiers.
struct MissionScene {
  std::string name;
  pex::bench::MissionMaps maps;
  std::size_t largest = 0;  // snapshot with the most map vertices
};

MissionScene& mission_scene(int which) {
  static std::map<int, std::unique_ptr<MissionScene>> cache;
  auto& slot = cache[which];
  if (slot) return *slot;
  slot = std::make_unique<MissionScene>();
  slot->name = which == 0 ? "campus" : "intel";
  pex::bench::MissionMapsOptions options;
  options.max_goals = 200;
  // The maps must not depend on the planner being measured: the robot
  // follows the reference planner (Boost's offset, the planner of before).
  auto greedy = planner_options(GoalStrategy::kGreedy);
  greedy.cspace.boost_offset = true;
  auto tight = greedy;
  tight.cspace.clearance_margin_m = 0.0;
  slot->maps = pex::bench::emulate_mission(
      std::string(PEX_SOURCE_DIR) + "/worlds/" + slot->name + ".wkt", options,
      [&](const TypedMultiPolygon& map, const pex::geometry::Pose2& pose, const std::vector<Point>& blacklist,
          const pex::planning::GoalFocus*) {
        // The mission's tight fallback: nothing reachable, plan once more without the margin.
        auto plan = plan_exploration(map, pose, blacklist, greedy);
        return plan.best_candidate() ? plan : plan_exploration(map, pose, blacklist, tight);
      });
  std::size_t most = 0;
  for (std::size_t i = 0; i < slot->maps.snapshots.size(); ++i) {
    const std::size_t v = pex::mapping::vertex_count(slot->maps.snapshots[i].map);
    if (v > most) {
      most = v;
      slot->largest = i;
    }
  }
  double area = 0.0;
  if (!slot->maps.snapshots.empty())
    for (const auto& p : slot->maps.snapshots.back().map) area += boost::geometry::area(p.geometry);
  std::fprintf(stderr, "mission %s: %zu snapshots, %d goals, %.0f m, done %d, largest map %zu vertices, last %.0f m2 %s\n",
               slot->name.c_str(), slot->maps.snapshots.size(), slot->maps.goals, slot->maps.travelled_m,
               slot->maps.done ? 1 : 0, most, area, slot->maps.error.c_str());
  return *slot;
}

// The mission of the benchmark's first argument; nullptr (the benchmark
// skipped, with the reason) when its maps did not load.
MissionScene* mission_scene_or_skip(benchmark::State& state) {
  MissionScene& s = mission_scene(static_cast<int>(state.range(0)));
  if (s.maps.snapshots.empty()) {
    state.SkipWithError((s.name + ": " + s.maps.error).c_str());
    return nullptr;
  }
  return &s;
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1)];
}

// The strategy of BM_Plan's and BM_PlanMission's second argument: 0 greedy,
// 1 the tour over every candidate, 2 the tour over the 10 nearest
// (TourOptions::horizon_candidates), each with the shipped first-leg bound.
PlannerOptions strategy_options(std::int64_t strategy) {
  auto o = planner_options(strategy == 0 ? GoalStrategy::kGreedy : GoalStrategy::kTour);
  if (strategy == 2) o.tour.horizon_candidates = 10;
  return o;
}
std::string strategy_label(std::int64_t strategy) {
  return strategy == 0 ? " greedy" : strategy == 1 ? " tour" : " tour, horizon 10";
}

// One whole plan_exploration call (what the explorer's worker runs every
// replan period) on the largest map of the mission.
void BM_Plan(benchmark::State& state) {
  MissionScene* scene = mission_scene_or_skip(state);
  if (!scene) return;
  MissionScene& s = *scene;
  const auto options = strategy_options(state.range(1));
  const auto& snap = s.maps.snapshots[s.largest];
  Plan plan;
  for (auto _ : state) {
    plan = plan_exploration(snap.map, snap.pose, snap.blacklist, options);
    benchmark::DoNotOptimize(plan);
  }
  state.SetLabel(s.name + strategy_label(state.range(1)));
  state.counters["map_vertices"] = static_cast<double>(pex::mapping::vertex_count(snap.map));
  state.counters["reflex"] = plan.stats.reflex_nodes;
  state.counters["candidates"] = static_cast<double>(plan.candidates.size());
  state.counters["ok"] = plan.ok ? 1 : 0;
}

// The steps of BM_Plan's greedy plan one by one, on the same map: the C-space
// (range 1 = 0), then the robot's row of the path matrix over its candidates
// (1): the rest of a plan is candidates and approach points.
void BM_PlanStep(benchmark::State& state) {
  MissionScene* scene = mission_scene_or_skip(state);
  if (!scene) return;
  MissionScene& s = *scene;
  const auto options = planner_options(GoalStrategy::kGreedy);
  const auto& snap = s.maps.snapshots[s.largest];
  ConfigurationSpace cs;
  cs.build(snap.map, options.cspace);
  const auto plan = plan_exploration(snap.map, snap.pose, snap.blacklist, options);
  std::vector<Point> targets;
  for (const auto& c : plan.candidates) targets.push_back(c.position);
  const auto start = cs.nearest_interior_point(Point(snap.pose.x_m, snap.pose.y_m), options.start_snap_distance_m);
  for (auto _ : state) {
    if (state.range(1) == 0) {
      ConfigurationSpace fresh;
      benchmark::DoNotOptimize(fresh.build(snap.map, options.cspace));
    } else if (start) {
      benchmark::DoNotOptimize(
          shortest_path_matrix(cs, *start, targets, PathMatrixOptions{.between_targets = false}));
    }
  }
  state.SetLabel(s.name + (state.range(1) == 0 ? " cspace" : " start row"));
}

// enclosed_areas on testing::islands_in_a_long_hole (a hostile MAP within
// the explorer's max_map_vertices). Counter: islands not placed in their hole.
void BM_EnclosedAreasHostile(benchmark::State& state) {
  const auto map = testing::islands_in_a_long_hole(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  int not_placed = 0;
  for (auto _ : state) benchmark::DoNotOptimize(enclosed_areas(map, &not_placed));
  state.counters["not_placed"] = not_placed;
}

// The whole plan on that map, the robot in the ring between the square and
// the hole (shipped planner options).
void BM_PlanHostile(benchmark::State& state) {
  const auto map = testing::islands_in_a_long_hole(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  PlannerOptions options;
  options.min_enclosed_area_m2 = 2.0;
  options.enclosed_goal_range_m = 4.0;
  Plan plan;
  for (auto _ : state) plan = plan_exploration(map, Pose2{2.0, 2.0, 0.0}, {}, options);
  state.counters["ok"] = plan.ok;
  state.counters["candidates"] = static_cast<double>(plan.candidates.size());
  state.counters["not_placed"] = plan.stats.polygons_not_placed;
}

// Every map of the mission planned once, in order, with the offset tiles
// kept from plan to plan as the explorer's worker keeps them: the per-plan
// CPU time's p50, p99 and max over the mission (the target is the p99).
void BM_PlanMission(benchmark::State& state) {
  MissionScene* scene = mission_scene_or_skip(state);
  if (!scene) return;
  MissionScene& s = *scene;
  const auto options = strategy_options(state.range(1));
  std::vector<double> ms;
  for (auto _ : state) {
    ms.clear();
    pex::planning::PlanCache cache;
    for (const auto& snap : s.maps.snapshots) {
      const double t0 = thread_cpu_ms();
      benchmark::DoNotOptimize(plan_exploration(snap.map, snap.pose, snap.blacklist, options, nullptr, nullptr, &cache));
      ms.push_back(thread_cpu_ms() - t0);
    }
  }
  state.SetLabel(s.name + strategy_label(state.range(1)));
  state.counters["plans"] = static_cast<double>(ms.size());
  state.counters["p50_ms"] = percentile(ms, 0.5);
  state.counters["p99_ms"] = percentile(ms, 0.99);
  state.counters["max_ms"] = percentile(ms, 1.0);
}

// What keep-out lines (planning/keep_out.hpp) cost the explorer's plans:
// every map of the mission planned once in order as its worker plans it
// (compute_plan, the offset tiles kept, each map with the live view of a
// scan from the simulator's laser at the snapshot's pose), with no keep-out
// (range 1 = 0) and with every wall of the world drawn as a keep-out line
// 0.05 m wide (1; the worst case: a glass floor of make-office-floor.py
// draws 45 of its 103 walls). Each map is planned once (the explorer plans
// every replan_period_ms on the newest MAP, which comes as often: a new map
// each time, so the planning thread's KeepOutCache gains nothing here; it
// does when plans outnumber maps: tight plans, ways home). Counters as
// BM_PlanMission's, per plan; and the keep-out's size and what parsing it
// cost.
struct KeepOutScene {
  std::vector<std::shared_ptr<const TypedMultiPolygon>> maps;  // the mission's snapshots
  std::vector<std::shared_ptr<const TypedMultiPolygon>> views;  // a live view at each
  std::shared_ptr<const TypedMultiPolygon> keep_out;
  int lines = 0;
  std::size_t vertices = 0;  // of the keep-out polygons
  double parse_ms = 0.0;     // CPU time parse_keep_out took (the explorer's start)
  std::string error;
};

const KeepOutScene& keep_out_scene(int which) {
  static std::map<int, std::unique_ptr<KeepOutScene>> cache;
  auto& slot = cache[which];
  if (slot) return *slot;
  slot = std::make_unique<KeepOutScene>();
  const MissionScene& mission = mission_scene(which);
  const auto world = pex::bench::read_world(std::string(PEX_SOURCE_DIR) + "/worlds/" + mission.name + ".wkt",
                                            slot->error);
  if (!world) return *slot;
  std::string text;
  char line[160];
  for (const auto& w : world->walls) {
    std::snprintf(line, sizeof line, "LINESTRING (%.6f %.6f, %.6f %.6f)\n", w.x0, w.y0, w.x1, w.y1);
    text += line;
  }
  // The emulated mission's maps are in the world's frame (emulate_mission).
  const double parse_started = thread_cpu_ms();
  auto parsed = parse_keep_out(text, "walls", pex::geometry::Pose2{}, 0.05);
  slot->parse_ms = thread_cpu_ms() - parse_started;
  if (const auto* e = std::get_if<KeepOutError>(&parsed)) {
    slot->error = e->message;
    return *slot;
  }
  slot->lines = std::get<KeepOut>(parsed).lines;
  slot->vertices = pex::mapping::vertex_count(std::get<KeepOut>(parsed).obstacles);
  slot->keep_out = std::make_shared<const TypedMultiPolygon>(std::move(std::get<KeepOut>(parsed).obstacles));
  const pex::sim::RayCaster caster(*world);
  pex::sim::Laser laser(pex::sim::LaserOptions{}, 13);
  LiveViewOptions view;
  view.range_m = 3.0;  // config/explorer.toml
  for (const auto& snap : mission.maps.snapshots) {
    auto map = std::make_shared<const TypedMultiPolygon>(snap.map);
    const auto ranges = laser.scan(caster, snap.pose);
    slot->views.push_back(std::make_shared<const TypedMultiPolygon>(
        live_view(ranges, laser.options().first_angle_rad(), laser.options().step_deg * M_PI / 180.0,
                  laser.options().min_range_m, snap.pose, view, map.get())));
    slot->maps.push_back(std::move(map));
  }
  return *slot;
}

void BM_PlanMissionKeepOut(benchmark::State& state) {
  MissionScene* mission = mission_scene_or_skip(state);
  if (!mission) return;
  const KeepOutScene& s = keep_out_scene(static_cast<int>(state.range(0)));
  if (!s.error.empty()) {
    state.SkipWithError((mission->name + ": " + s.error).c_str());
    return;
  }
  const bool keep_out = state.range(1) != 0;
  std::vector<double> ms;
  int failed = 0, keep_out_failed = 0;
  for (auto _ : state) {
    ms.clear();
    failed = 0;
    keep_out_failed = 0;
    PlanCache cache;
    for (std::size_t i = 0; i < s.maps.size(); ++i) {
      PlanRequest request;
      request.map = s.maps[i];
      request.pose = mission->maps.snapshots[i].pose;
      request.blacklist = mission->maps.snapshots[i].blacklist;
      request.options = planner_options(GoalStrategy::kGreedy);
      request.live_view = s.views[i];
      if (keep_out) request.keep_out = s.keep_out;
      const double t0 = thread_cpu_ms();
      const auto result = compute_plan(request, &cache);
      ms.push_back(thread_cpu_ms() - t0);
      failed += result.plan.ok ? 0 : 1;
      keep_out_failed += result.keep_out_failed ? 1 : 0;
      benchmark::DoNotOptimize(result);
    }
  }
  state.SetLabel(mission->name + (keep_out ? " keep-out: every wall" : " no keep-out"));
  state.counters["plans"] = static_cast<double>(ms.size());
  state.counters["not_ok"] = failed;
  state.counters["keep_out_failed"] = keep_out_failed;
  state.counters["lines"] = keep_out ? s.lines : 0;
  state.counters["keep_out_vertices"] = keep_out ? static_cast<double>(s.vertices) : 0.0;
  state.counters["parse_ms"] = keep_out ? s.parse_ms : 0.0;
  state.counters["p50_ms"] = percentile(ms, 0.5);
  state.counters["p99_ms"] = percentile(ms, 0.99);
  state.counters["max_ms"] = percentile(ms, 1.0);
}

// The scan guard's reading of one scan (guard_points: the returns and the
// points past wall ends and on to convex corners) and its check of one arc
// on them, which the explorer runs on its one LCM thread for every
// LIDAR_SCAN (25 Hz) and every control step (10 Hz): 200 noisy LMS1xx scans
// (the simulator's laser, seed 5) from random poses in worlds/office.wkt
// with at least 0.3 m to every wall; reach 0 is the returns alone.
struct GuardScans {
  std::vector<std::vector<float>> scans;
  pex::sim::LaserOptions laser;
};

const GuardScans* guard_scans(benchmark::State& state) {
  static const std::optional<GuardScans> scans = []() -> std::optional<GuardScans> {
    std::string error;
    const auto world = pex::bench::read_world(std::string(PEX_SOURCE_DIR) + "/worlds/office.wkt", error);
    if (!world) return std::nullopt;
    GuardScans out;
    const pex::sim::RayCaster caster(*world);
    pex::sim::Laser laser(out.laser, 5);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> x(world->min_x, world->max_x), y(world->min_y, world->max_y),
        heading(-3.14159, 3.14159);
    while (out.scans.size() < 200) {
      const pex::sim::Pose2 pose{x(rng), y(rng), heading(rng)};
      if (caster.clearance(pose.x_m, pose.y_m, 1.0) < 0.3) continue;
      out.scans.push_back(laser.scan(caster, pose));
    }
    return out;
  }();
  if (!scans) state.SkipWithError("worlds/office.wkt cannot be read");
  return scans ? &*scans : nullptr;
}

// guard_points on scan i with the reach of the benchmark's argument (mm).
std::vector<pex::mapping::Point> guard_of(const GuardScans& scans, std::size_t i, const benchmark::State& state) {
  pex::planning::GuardScanOptions options;
  options.wall_end_reach_m = static_cast<double>(state.range(0)) * 1e-3;
  const auto& laser = scans.laser;
  return pex::planning::guard_points(scans.scans[i], laser.first_angle_rad(), laser.step_deg * M_PI / 180.0,
                                     laser.min_range_m, laser.max_range_m, {}, options);
}

void BM_GuardPoints(benchmark::State& state) {
  const GuardScans* scans = guard_scans(state);
  if (!scans) return;
  const float max_range = static_cast<float>(scans->laser.max_range_m);
  std::size_t i = 0, points = 0, returns = 0;
  for (auto _ : state) {
    const std::size_t scan = i++ % scans->scans.size();
    const auto guard = guard_of(*scans, scan, state);
    benchmark::DoNotOptimize(guard.data());
    const auto& ranges = scans->scans[scan];
    points += guard.size();
    returns += static_cast<std::size_t>(
        std::count_if(ranges.begin(), ranges.end(), [&](float r) { return r < max_range; }));
  }
  state.counters["points_per_scan"] = static_cast<double>(points) / static_cast<double>(state.iterations());
  state.counters["returns_per_scan"] = static_cast<double>(returns) / static_cast<double>(state.iterations());
}

void BM_GuardArc(benchmark::State& state) {
  const GuardScans* scans = guard_scans(state);
  if (!scans) return;
  std::vector<std::vector<pex::mapping::Point>> guards;
  for (std::size_t scan = 0; scan < scans->scans.size(); ++scan) guards.push_back(guard_of(*scans, scan, state));
  std::size_t i = 0;
  for (auto _ : state) {
    // The guard's two checks of a step: the body and the body with its side margin.
    const auto& guard = guards[i++ % guards.size()];
    benchmark::DoNotOptimize(pex::planning::free_distance_along_arc(guard, 0.8, 0.25));
    benchmark::DoNotOptimize(pex::planning::free_distance_along_arc(guard, 0.8, 0.28));
  }
}

// What the guard's reading of the map's walls costs a LIDAR_SCAN (25 Hz)
// when every beam of a 541-beam LMS111 scan is without a return (the worst
// case: the laser blind all round), at the scene's candidates (C-space
// points, every heading in turn) on campus's and a 5000-vertex Intel map.
void BM_GuardMapWalls(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  if (!usable(state, s)) return;
  const std::vector<float> blind(541, std::numeric_limits<float>::infinity());
  const double angle_min = -0.75 * M_PI, step = 0.5 * M_PI / 180.0;
  std::size_t i = 0, filled_total = 0;
  for (auto _ : state) {
    const Point& p = s.candidates[i % s.candidates.size()];
    const pex::geometry::Pose2 sensor{p.x(), p.y(), 0.7 * static_cast<double>(i++)};
    int filled = 0;
    const auto ranges =
        pex::planning::ranges_with_map_walls(blind, angle_min, step, 0.05, 20.0, sensor, s.map, 2.0, &filled);
    benchmark::DoNotOptimize(ranges.data());
    filled_total += static_cast<std::size_t>(filled);
  }
  map_counters(state, s);
  state.counters["filled_per_scan"] = static_cast<double>(filled_total) / static_cast<double>(state.iterations());
}

void missions(benchmark::internal::Benchmark* b) {
  b->ArgNames({"world", "strategy"});
  for (const int w : {0, 1})
    for (const int t : {0, 1, 2}) b->Args({w, t});
}

void maps(benchmark::internal::Benchmark* b) { b->ArgNames({"map"})->Arg(0)->Arg(1); }
void maps_and_counts(benchmark::internal::Benchmark* b) {
  b->ArgNames({"map", "n"});
  for (const int map : {0, 1})
    for (const int n : {10, 30, 60}) b->Args({map, n});
}

BENCHMARK(BM_CSpace)->Apply(maps)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_ShortestPaths)->Apply(maps_and_counts)->Unit(benchmark::kMillisecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_StartRow)->Apply(maps_and_counts)->Unit(benchmark::kMillisecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_PathMatrix)->Apply(maps_and_counts)->Unit(benchmark::kMillisecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_Tour)->Apply(maps_and_counts)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_Plan)->Apply(missions)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_PlanStep)
    ->ArgNames({"world", "step"})
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_EnclosedAreasHostile)
    ->ArgNames({"hole", "islands"})
    ->Args({1000, 100})
    ->Args({100000, 100})
    ->Args({100000, 20000})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PlanHostile)
    ->ArgNames({"hole", "islands"})
    ->Args({1000, 100})
    ->Args({100000, 20000})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK(BM_PlanMissionKeepOut)
    ->ArgNames({"world", "keep_out"})
    ->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1})
    ->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3)->ReportAggregatesOnly(true);
BENCHMARK(BM_PlanMission)->Apply(missions)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_GuardPoints)->ArgName("reach_mm")->Arg(0)->Arg(30)->Unit(benchmark::kMicrosecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_GuardArc)->ArgName("reach_mm")->Arg(0)->Arg(30)->Unit(benchmark::kMicrosecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_GuardMapWalls)->Apply(maps)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_PlanTour)->Apply(maps_and_counts)->Unit(benchmark::kMillisecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);

}  // namespace

int main(int argc, char** argv) {
  pex::bench::MedianCollector reporter;
  reporter.run(&argc, argv);
  auto get = [&](const std::string& name) { return reporter.median(name); };
  std::printf("{");
  const char* sep = "";
  for (const int map : {0, 1}) {
    const char* name = map == 0 ? "campus" : "intel";
    for (const int n : {10, 30, 60}) {
      const std::string args = "map:" + std::to_string(map) + "/n:" + std::to_string(n);
      std::printf("%s\"%s_matrix_ms_%d\":%.3f,\"%s_tour_ms_%d\":%.3f,\"%s_plan_tour_ms_%d\":%.3f,"
                  "\"%s_greedy_search_ms_%d\":%.3f,\"%s_start_row_ms_%d\":%.3f",
                  sep, name, n, get("BM_PathMatrix/" + args), name, n, get("BM_Tour/" + args), name, n,
                  get("BM_PlanTour/" + args), name, n, get("BM_ShortestPaths/" + args), name, n,
                  get("BM_StartRow/" + args));
      sep = ",";
    }
    std::printf(",\"%s_cspace_ms\":%.3f", name, get("BM_CSpace/map:" + std::to_string(map)));
    // Whole plans on the emulated mission's maps (the target: p99).
    for (const int tour : {0, 1, 2}) {
      const std::string args = "world:" + std::to_string(map) + "/strategy:" + std::to_string(tour);
      const char* strategy = tour == 0 ? "greedy" : tour == 1 ? "tour" : "tour_h10";
      const auto counter = [&](const std::string& key) {
        const auto it = reporter.median_counter.find("BM_PlanMission/" + args + "/" + key);
        return it == reporter.median_counter.end() ? -1.0 : it->second;
      };
      std::printf(",\"%s_plan_%s_ms\":%.3f,\"%s_mission_%s_p50_ms\":%.3f,\"%s_mission_%s_p99_ms\":%.3f", name,
                  strategy, get("BM_Plan/" + args), name, strategy, counter("p50_ms"), name, strategy,
                  counter("p99_ms"));
    }
  }
  std::printf("}\n");
  return 0;
}
