// pex-bench-slam: the filter alone on a CARMEN log (default: the full Intel
// log) — accuracy by the relations metric, real-time factor, and micro
// benchmarks of the matcher. Figures are reported in docs/slam.md, never asserted.
//
//   pex-bench-slam [--logs DIR]           per CARMEN log with relations in DIR (default
//                                         ../shared/data): pex-carmen2lcm, then pex-slam --log
//                                         with config/slam.toml and config/datasets/slam.toml, one JSON line each
//   pex-bench-slam --laps N [--logs DIR]  the same with every log driven N times (forwards,
//                                         back, ...): memory and accuracy over run length
//   pex-bench-slam --gbench [gbench args] Google Benchmark run (full log once + micro)
//   pex-bench-slam --run CLF RELATIONS [POSES_OUT] [PARTICLES] [SEED]
//                                         one run, one JSON line
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numbers>
#include <iostream>
#include <string>
#include <filesystem>
#include <sstream>
#include <unordered_set>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "carmen_run.hpp"
#include "evaluation/laps.hpp"
#include "evaluation/odometry_direction.hpp"

namespace {

std::string shared_data(const char* file) { return std::string(PEX_SHARED_DIR) + "/data/" + file; }

// The log as pex-carmen2lcm writes it by default: steps driven backwards but
// logged forwards turned round (raw_odometry: as logged).
pex::evaluation::CarmenLog load_log(const std::string& path, bool raw_odometry = false) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  pex::evaluation::CarmenLog log = pex::evaluation::parse_carmen_log(in);
  if (!raw_odometry) pex::evaluation::correct_odometry_direction(log);
  return log;
}

std::vector<pex::evaluation::Relation> load_relations(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  return pex::evaluation::read_relations(in).relations;
}

int run_once(int argc, char** argv) {
  bool raw_odometry = false;
  int laps = 1;
  for (int i = 7; i < argc; ++i) {
    raw_odometry = raw_odometry || std::strcmp(argv[i], "raw_odometry=1") == 0;
    if (std::strncmp(argv[i], "laps=", 5) == 0) laps = std::stoi(argv[i] + 5);
  }
  const auto logged = load_log(argv[2], raw_odometry);
  const auto log = pex::evaluation::lap_log(logged, laps, 1.0);
  const auto relations = pex::evaluation::lap_relations(load_relations(argv[3]), pex::evaluation::lap_timing(logged, 1.0), laps);
  pex::slam::ParticleFilterOptions options;
  if (argc > 5) options.particle_count = std::stoi(argv[5]);
  if (argc > 6) options.seed = std::stoull(argv[6]);
  bool odometry_from_laser = true;
  pex::slam::OdometrySyncOptions sync;
  std::string trace_path;
  // Experiments: key=value overrides of the defaults.
  for (int i = 7; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto eq = arg.find('=');
    if (eq == std::string::npos) throw std::runtime_error("expected key=value: " + arg);
    const std::string key = arg.substr(0, eq);
    if (key == "trace") {  // per update: time, N_eff, resampled, distinct ancestors 10/50/200 updates back, best pose
      trace_path = arg.substr(eq + 1);
      continue;
    }
    const double v = std::stod(arg.substr(eq + 1));
    if (key == "linear_update_m") options.linear_update_m = v;
    else if (key == "angular_update_rad") options.angular_update_rad = v;
    else if (key == "standing_update_s") options.standing_update_s = v;
    else if (key == "score_sigma_m2") options.grid.score_sigma_m2 = v;
    else if (key == "likelihood_sigma_m2") options.grid.likelihood_sigma_m2 = v;
    else if (key == "kernel_radius_cells") options.grid.kernel_radius_cells = static_cast<int>(v);
    else if (key == "beam_step") options.grid.beam_step = static_cast<int>(v);
    else if (key == "resolution_m") options.grid.resolution_m = v;
    else if (key == "usable_range_m") options.scan.usable_range_m = v;
    else if (key == "refinements") options.matcher.refinements = static_cast<int>(v);
    else if (key == "linear_step_m") options.matcher.linear_step_m = v;
    else if (key == "angular_step_rad") options.matcher.angular_step_rad = v;
    else if (key == "use_motion_prior") options.proposal.use_motion_prior = v != 0.0;
    else if (key == "min_linear_std_m") options.proposal.min_linear_std_m = v;
    else if (key == "min_angular_std_rad") options.proposal.min_angular_std_rad = v;
    else if (key == "along_line_weight") options.grid.along_line_weight = v;
    else if (key == "line_flatness") options.grid.line_flatness = v;
    else if (key == "check_free") options.grid.check_free_before_hit = v != 0.0;
    else if (key == "match_beam_step") options.matcher.beam_step = static_cast<int>(v);
    else if (key == "match_beam_spacing_deg") options.matcher.beam_spacing_rad = v * std::numbers::pi / 180.0;
    else if (key == "proposal_beam_spacing_deg") options.proposal.beam_spacing_rad = v * std::numbers::pi / 180.0;
    else if (key == "threads") options.threads = static_cast<int>(v);
    else if (key == "sample_scale") options.proposal.sample_scale = v;
    else if (key == "linear_offset_m") options.proposal.linear_offset_m = v;
    else if (key == "angular_offset_rad") options.proposal.angular_offset_rad = v;
    else if (key == "likelihood_gain") options.likelihood_gain = v;
    else if (key == "srr") options.motion.srr = v;
    else if (key == "srt") options.motion.srt = v;
    else if (key == "str") options.motion.str = v;
    else if (key == "stt") options.motion.stt = v;
    else if (key == "odometry_from_laser") odometry_from_laser = v != 0.0;
    else if (key == "raw_odometry" || key == "laps") continue;  // read before the log was loaded
    else if (key == "odometry_lead_s") sync.odometry_lead_us = std::llround(v * 1e6);
    else if (key == "estimate_lead") sync.estimate_lead = v != 0.0;
    else if (key == "resample_threshold") options.resample_threshold = v;
    else if (key == "odometry_check") options.odometry_check.enabled = v != 0.0;
    else if (key == "odometry_check_margin") options.odometry_check.margin = v;
    else if (key == "odometry_check_halves" && v != 0.0)
      options.odometry_check.translation_scales = {0.5, 0.0, -0.5, -1.0};
    else throw std::runtime_error("unknown key " + key);
  }
  const auto start = std::chrono::steady_clock::now();
  std::ofstream trace;
  if (!trace_path.empty()) trace.open(trace_path);
  auto after_update = [&trace](const pex::slam::ParticleFilter& filter, std::int64_t utime) {
    if (!trace.is_open()) return;
    // How many distinct ancestors the particle set has k updates back: 1 means
    // every particle shares that part of its trajectory (and map).
    auto ancestors = [&filter](std::int64_t back) {
      std::vector<const pex::slam::TrajectoryNode*> roots;
      for (const auto& p : filter.particles()) {
        const pex::slam::TrajectoryNode* n = p.trajectory.get();
        while (n && n->generation > filter.generation() - back) n = n->parent.get();
        roots.push_back(n);
      }
      std::sort(roots.begin(), roots.end());
      return std::unique(roots.begin(), roots.end()) - roots.begin();
    };
    const auto& best = filter.particles()[filter.best_index()];
    trace << static_cast<double>(utime) * 1e-6 << ' ' << filter.generation() << ' '
          << filter.last_update().effective_sample_size << ' ' << filter.last_update().resampled << ' '
          << ancestors(10) << ' ' << ancestors(50) << ' ' << ancestors(200) << ' ' << best.pose.x_m << ' '
          << best.pose.y_m << ' ' << best.pose.theta_rad << ' ' << filter.last_update().odometry_scale << ' '
          << filter.last_update().odometry_check_ratio;
    // Every 50 updates, what the particles hold: distinct map tiles (shared
    // ones once) and trajectory nodes.
    if (filter.generation() % 50 == 0) {
      std::unordered_set<const void*> tiles, nodes;
      for (const auto& p : filter.particles()) {
        for (const auto* tile : dynamic_cast<const pex::slam::CowGridMap&>(*p.map).tiles()) tiles.insert(tile);
        for (const pex::slam::TrajectoryNode* n = p.trajectory.get(); n && nodes.insert(n).second; n = n->parent.get()) {
        }
      }
      trace << " tiles " << tiles.size() << " best_map_tiles "
            << dynamic_cast<const pex::slam::CowGridMap&>(*best.map).tile_count() << " nodes " << nodes.size();
    }
    trace << '\n';
  };
  auto run = pex::bench::run_filter_on_carmen(log, options, odometry_from_laser, sync, after_update);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::stable_sort(run.poses.begin(), run.poses.end(),
                   [](const auto& a, const auto& b) { return a.timestamp_s < b.timestamp_s; });
  // The trajectory as pex-slam --poses writes it: each update's correction
  // spread over the scans before it; the carried-forward one's error beside.
  const auto carried = pex::evaluation::evaluate_relations(run.poses, relations);
  std::stable_sort(run.spread_poses.begin(), run.spread_poses.end(),
                   [](const auto& a, const auto& b) { return a.timestamp_s < b.timestamp_s; });
  pex::evaluation::MetricOptions split;
  split.split_gap_s = 100.0;
  const auto metric = pex::evaluation::evaluate_relations(run.spread_poses, relations, split);
  if (argc > 4 && std::strcmp(argv[4], "-") != 0) {
    std::ofstream out(argv[4]);
    out.precision(17);
    for (const auto& p : run.spread_poses)
      out << p.timestamp_s << ' ' << p.pose.x_m << ' ' << p.pose.y_m << ' ' << p.pose.theta_rad << '\n';
  }
  if (trace.is_open())
    for (const std::int64_t lead : run.odometry_lead_us_per_update) trace << "# lead_us " << lead << '\n';
  std::string json = pex::evaluation::to_json_line(metric);
  json.pop_back();
  std::printf("%s,\"carried_forward_trans_mean_m\":%.6f,\"carried_forward_rot_mean_deg\":%.6f,\"odometry_lead_s\":%.3f,\"corrected_odometry_steps\":%lld,\"updates\":%lld,\"resamplings\":%lld,\"evaluations\":%lld,\"seconds\":%.3f,\"realtime_factor\":%.1f}\n",
              json.c_str(), carried.trans_mean_m, carried.rot_mean_deg, static_cast<double>(run.odometry_lead_us) * 1e-6,
              static_cast<long long>(run.corrected_odometry_steps), static_cast<long long>(run.updates),
              static_cast<long long>(run.resamplings),
              static_cast<long long>(run.matcher_evaluations), seconds, run.log_duration_s / seconds);
  return 0;
}

void BM_IntelFullLog(benchmark::State& state) {
  const auto log = load_log(shared_data("intel.clf"));
  const auto relations = load_relations(shared_data("intel.relations"));
  pex::slam::ParticleFilterOptions options;
  options.particle_count = static_cast<int>(state.range(0));
  options.threads = static_cast<int>(state.range(1));
  pex::bench::CarmenRunResult run;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    run = pex::bench::run_filter_on_carmen(log, options);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  std::stable_sort(run.spread_poses.begin(), run.spread_poses.end(),
                   [](const auto& a, const auto& b) { return a.timestamp_s < b.timestamp_s; });
  const auto metric = pex::evaluation::evaluate_relations(run.spread_poses, relations);
  state.counters["trans_mean_m"] = metric.trans_mean_m;
  state.counters["trans_std_m"] = metric.trans_std_m;
  state.counters["rot_mean_deg"] = metric.rot_mean_deg;
  state.counters["rot_std_deg"] = metric.rot_std_deg;
  state.counters["relations"] = static_cast<double>(metric.relations);
  state.counters["realtime_factor"] = run.log_duration_s / seconds;
  state.counters["updates"] = static_cast<double>(run.updates);
}
// Args: particles, threads. One iteration: the full log takes tens of seconds.
BENCHMARK(BM_IntelFullLog)->Args({30, 1})->Args({30, 2})->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// A map of the first 300 Intel scans at their odometry poses, and a scan to score.
struct IntelMapFixture {
  pex::slam::CowGridMap map{pex::slam::CowGridMapOptions{}};
  pex::slam::ScanPoints scan;
  pex::geometry::Pose2 pose;
  IntelMapFixture() {
    const auto log = load_log(shared_data("intel.clf"));
    for (std::size_t i = 0; i < 300 && i < log.lasers.size(); ++i) {
      pex::slam::RangeScan range;
      range.angle_min_rad = log.lasers[i].angle_min_rad;
      range.angle_increment_rad = log.lasers[i].angle_increment_rad;
      range.range_max_m = log.lasers[i].max_range_m;
      range.ranges_m = log.lasers[i].ranges_m;
      scan = pex::slam::to_scan_points(range, {});
      pose = log.lasers[i].odometry;
      map.insert(pose, scan);
    }
  }
};

// One evaluate(): the matcher's inner loop (score and likelihood of every beam).
void BM_CowGridMapEvaluate(benchmark::State& state) {
  static const IntelMapFixture fixture;
  double sink = 0.0;
  for (auto _ : state) {
    sink += fixture.map.evaluate(fixture.pose, fixture.scan).score;
    benchmark::DoNotOptimize(sink);
  }
  state.counters["beams"] = static_cast<double>(fixture.scan.beams.size());
}
BENCHMARK(BM_CowGridMapEvaluate);

// Resampling's copy and the first write after it (copy-on-write of touched tiles).
void BM_CowGridMapCloneAndInsert(benchmark::State& state) {
  static const IntelMapFixture fixture;
  for (auto _ : state) {
    auto copy = fixture.map.clone();
    copy->insert(fixture.pose, fixture.scan);
    benchmark::DoNotOptimize(copy.get());
  }
  state.counters["tiles"] = static_cast<double>(fixture.map.tile_count());
}
BENCHMARK(BM_CowGridMapCloneAndInsert);

}  // namespace

// Runs argv, waits; its exit status and peak resident memory (MB) and wall time.
struct ChildRun {
  int status = -1;
  double peak_mb = 0.0;
  double wall_s = 0.0;
  double cpu_s = 0.0;  // user + system
};
ChildRun run_child(const std::vector<std::string>& args, const std::string& stdout_path) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    if (!stdout_path.empty() && !std::freopen(stdout_path.c_str(), "w", stdout)) _exit(127);
    execv(argv[0], argv.data());
    _exit(127);
  }
  ChildRun r;
  struct rusage usage {};
  int status = 0;
  if (pid > 0 && wait4(pid, &status, 0, &usage) == pid) {
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KB on Linux
    auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
    r.cpu_s = seconds(usage.ru_utime) + seconds(usage.ru_stime);
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

// One CARMEN log through the shipped pipeline (pex-carmen2lcm [--laps N],
// pex-slam --log with config/slam.toml and config/datasets/slam.toml), scored by the relations metric (in
// every lap for N > 1). The JSON line's fields, or "" when a step failed.
std::string run_log(const std::filesystem::path& clf, const std::filesystem::path& relations_path, int laps,
                    const std::filesystem::path& work) {
  namespace fs = std::filesystem;
  const fs::path bin = fs::canonical("/proc/self/exe").parent_path();
  const std::string name = clf.stem().string();
  const fs::path lcm = work / (name + ".lcm"), poses = work / (name + ".poses");
  if (run_child({(bin / "pex-carmen2lcm").string(), clf.string(), lcm.string(), "--laps", std::to_string(laps)},
                "/dev/null")
          .status != 0) {
    std::fprintf(stderr, "pex-bench-slam: pex-carmen2lcm failed on %s\n", clf.c_str());
    return "";
  }
  const ChildRun slam = run_child({(bin / "pex-slam").string(), "--config",
                                   std::string(PEX_SOURCE_DIR) + "/config/slam.toml", "--config",
                                   std::string(PEX_SOURCE_DIR) + "/config/datasets/slam.toml", "--log", lcm.string(),
                                   "--poses", poses.string(), "--log-level", "warn"},
                                  "/dev/null");
  fs::remove(lcm);
  if (slam.status != 0) {
    std::fprintf(stderr, "pex-bench-slam: pex-slam failed on %s\n", clf.c_str());
    return "";
  }
  std::ifstream poses_in(poses);
  const auto estimated = pex::evaluation::read_poses(poses_in);
  fs::remove(poses);
  const auto log = load_log(clf.string());
  const auto timing = pex::evaluation::lap_timing(log, 1.0);  // pex-carmen2lcm's default gap
  const auto relations = load_relations(relations_path.string());
  const auto lapped = pex::evaluation::lap_relations(relations, timing, laps);  // grouped by lap
  const auto metric = pex::evaluation::evaluate_relations(estimated.poses, lapped);
  const double lap_s = timing.last_s - timing.first_s;
  const double log_s = laps * lap_s + (laps - 1) * timing.gap_s;
  char fields[1024];
  std::snprintf(fields, sizeof fields,
                "\"log\":\"%s\",\"relations\":%zu,\"trans_mean_m\":%.6f,\"trans_std_m\":%.6f,"
                "\"rot_mean_deg\":%.6f,\"rot_std_deg\":%.6f,\"wall_s\":%.2f,\"log_s\":%.1f,\"rtf\":%.1f,"
                "\"peak_mb\":%.1f,\"cpu_s\":%.2f",
                name.c_str(), metric.relations, metric.trans_mean_m, metric.trans_std_m, metric.rot_mean_deg,
                metric.rot_std_deg, slam.wall_s, log_s, slam.wall_s > 0 ? log_s / slam.wall_s : 0.0, slam.peak_mb,
                slam.cpu_s);
  std::string json = fields;
  if (laps > 1) {
    // Each lap's relations alone: does the filter stay as good lap after lap?
    json += ",\"laps\":" + std::to_string(laps) + ",\"lap_trans_mean_m\":[";
    for (int lap = 0; lap < laps; ++lap) {
      const auto first = lapped.begin() + static_cast<std::ptrdiff_t>(lap * relations.size());
      const std::vector<pex::evaluation::Relation> one(first, first + static_cast<std::ptrdiff_t>(relations.size()));
      char value[32];
      std::snprintf(value, sizeof value, "%s%.4f", lap == 0 ? "" : ",",
                    pex::evaluation::evaluate_relations(estimated.poses, one).trans_mean_m);
      json += value;
    }
    json += "]";
  }
  return json;
}

// scripts/bench.sh slam: every log of the data folder through the shipped
// pipeline, one JSON line per log (issue 13's fields, and the CPU time).
int run_logs(const std::string& dir, int laps) {
  namespace fs = std::filesystem;
  const fs::path work = fs::temp_directory_path() / ("pex-bench-slam-" + std::to_string(getpid()));
  fs::create_directories(work);
  std::vector<fs::path> logs;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().extension() == ".clf" && fs::exists(fs::path(entry.path()).replace_extension(".relations")))
      logs.push_back(entry.path());
  std::sort(logs.begin(), logs.end());
  int failures = 0;
  for (const fs::path& clf : logs) {
    const std::string fields = run_log(clf, fs::path(clf).replace_extension(".relations"), laps, work);
    if (fields.empty()) {
      ++failures;
      continue;
    }
    std::printf("{%s}\n", fields.c_str());
    std::fflush(stdout);
  }
  fs::remove_all(work);
  return failures == 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  if (argc == 1 || (argc == 3 && std::strcmp(argv[1], "--logs") == 0) ||
      ((argc == 3 || argc == 5) && std::strcmp(argv[1], "--laps") == 0)) {
    try {
      // --laps N [--logs DIR]: every log driven N times (forwards, back, ...):
      // memory and accuracy over run length.
      const int laps = argc > 1 && std::strcmp(argv[1], "--laps") == 0 ? std::stoi(argv[2]) : 1;
      if (laps < 1) throw std::runtime_error("--laps must be at least 1");
      std::string dir = std::string(PEX_SHARED_DIR) + "/data";
      if (argc == 3 && std::strcmp(argv[1], "--logs") == 0) dir = argv[2];
      if (argc == 5 && std::strcmp(argv[3], "--logs") == 0) dir = argv[4];
      return run_logs(dir, laps);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "pex-bench-slam: %s\n", e.what());
      return 2;
    }
  }
  if (argc >= 2 && std::strcmp(argv[1], "--gbench") == 0) {
    argv[1] = argv[0];
    ++argv;
    --argc;
  }
  if (argc >= 4 && std::strcmp(argv[1], "--run") == 0) {
    try {
      return run_once(argc, argv);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "pex-bench-slam: %s\n", e.what());
      return 2;
    }
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
