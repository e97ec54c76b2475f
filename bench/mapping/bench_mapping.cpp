// pex-bench-mapping: one scan inserted into polygon maps of 1k, 10k and 100k
// vertices (typed and plain), the share of the reassignment pass, bytes per
// vertex and map bytes against a 5 cm occupancy grid. Figures are reported
// (docs/mapping.md), never asserted. The last stdout line is one JSON object.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "median_collector.hpp"
#include "carmen_scans.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"
#include "mapping/test_support.hpp"

namespace {

using namespace pex::mapping;
using pex::geometry::Pose2;

constexpr double kSpacingM = 2.0;  // rock lattice
const testing::ScanSpec kSpec{};   // 270 degrees, 541 beams, 10 m

ScanPolygonOptions scan_options() {
  ScanPolygonOptions o;
  o.range_max_m = 8.0;
  o.free_range_m = 4.0;
  return o;
}

struct Fixture {
  PolygonMap map;
  std::vector<TypedPolygon> next_scans;  // scans not yet in the map, at its frontier
  bool filled = false;

  // Grows the map until its planning map has `target_vertices`; keeps the
  // scans after that for timing.
  void take(TypedPolygon scan, std::size_t target_vertices) {
    if (filled) {
      next_scans.push_back(std::move(scan));
      return;
    }
    map.insert(scan);
    filled = map.planning_vertex_count() >= target_vertices;
  }
};

// Drives a lawnmower path through a rock field until the planning map has at
// least `target_vertices`, then keeps the following scans for timing.
std::unique_ptr<Fixture> build(std::size_t target_vertices, bool typed) {
  std::mt19937_64 rng(42);
  // Side length so that the field holds the target with room to spare (the
  // path adds ~20 planning vertices a scan, a scan every 4.5 m2).
  const double side = std::max(24.0, std::sqrt(static_cast<double>(target_vertices) * 0.4));
  const auto walls = testing::rock_field(side, side, kSpacingM, rng);
  auto fixture = std::make_unique<Fixture>();
  PolygonMapOptions options;
  options.assign_edge_types = typed;
  fixture->map = PolygonMap(options);
  const auto o = scan_options();
  int row = 0;
  for (double y = 1.0; y < side - 1.0 && fixture->next_scans.size() < 32; y += 3.0, ++row) {
    for (double s = 1.0; s < side - 1.0 && fixture->next_scans.size() < 32; s += 1.5) {
      const double x = row % 2 == 0 ? s : side - s;
      const Pose2 pose{x, y, row % 2 == 0 ? 0.0 : 3.14159};
      auto scan = scan_to_polygon(testing::cast_scan(walls, pose, kSpec), kSpec.angle_min,
                                  kSpec.angle_increment, pose, o);
      if (scan.ok) fixture->take(std::move(scan.polygon), target_vertices);
    }
  }
  return fixture;
}

Fixture& fixture(std::size_t vertices, bool typed) {
  static std::map<std::pair<std::size_t, bool>, std::unique_ptr<Fixture>> cache;
  auto& slot = cache[{vertices, typed}];
  if (!slot) slot = build(vertices, typed);
  return *slot;
}

// Real scans: the Intel lab log (../shared/data/intel.clf, 180 beams, indoor)
// at its logged laser poses (raw odometry: it drifts, but over the part of the
// log that grows a map to 1k-5k vertices it stays a building), inserted with
// the mapper's defaults (a scan after 0.2 m or 0.25 rad of motion) until the
// planning map has `target_vertices`; the next scans are kept for timing.
std::unique_ptr<Fixture> build_intel(std::size_t target_vertices) {
  auto fixture = std::make_unique<Fixture>();
  const ScanPolygonOptions options;
  // No data: the fixture stays empty and the benchmark reports an error.
  pex::bench::for_each_moved_scan(std::string(PEX_SHARED_DIR) + "/data/intel.clf",
                                  [&](const std::vector<float>& ranges, const auto& laser, const Pose2& pose) {
                                    auto scan = scan_to_polygon(ranges, laser.angle_min_rad,
                                                                laser.angle_increment_rad, pose, options);
                                    if (scan.ok) fixture->take(std::move(scan.polygon), target_vertices);
                                    return fixture->next_scans.size() < 32;
                                  });
  return fixture;
}

Fixture& intel_fixture(std::size_t vertices) {
  static std::map<std::size_t, std::unique_ptr<Fixture>> cache;
  auto& slot = cache[vertices];
  if (!slot) slot = build_intel(vertices);
  return *slot;
}

// with_planning: the insert and then the planning layer of the tiles it
// replaced (what publishing the map right after this insert would add).
void insert_benchmark(benchmark::State& state, bool typed, bool with_planning = false, bool intel = false) {
  const auto vertices = static_cast<std::size_t>(state.range(0));
  Fixture& f = intel ? intel_fixture(vertices) : fixture(vertices, typed);
  if (f.next_scans.empty()) {
    state.SkipWithError(intel ? "no intel.clf, or the log ended before the map reached the size"
                              : "the rock field was explored before the map reached the size");
    return;
  }
  std::size_t k = 0;
  double tiles_touched = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    PolygonMap copy = f.map;  // copy-on-write: shares every tile
    const TypedPolygon& scan = f.next_scans[k++ % f.next_scans.size()];
    state.ResumeTiming();
    auto result = copy.insert(scan);
    benchmark::DoNotOptimize(result);
    tiles_touched += result.tiles_touched;
    if (with_planning) benchmark::DoNotOptimize(copy.planning_vertex_count());
    state.PauseTiming();
    {
      PolygonMap discard = std::move(copy);  // tile release outside the timing
    }
    state.ResumeTiming();
  }
  state.counters["map_vertices"] = static_cast<double>(f.map.planning_vertex_count());
  state.counters["tiles"] = static_cast<double>(f.map.tile_count());
  state.counters["tiles_touched"] = tiles_touched / static_cast<double>(std::max<std::size_t>(1, k));
}

void BM_InsertTyped(benchmark::State& state) { insert_benchmark(state, true); }
void BM_InsertPlain(benchmark::State& state) { insert_benchmark(state, false); }
void BM_InsertTypedThenPlanning(benchmark::State& state) { insert_benchmark(state, true, true); }
void BM_InsertIntel(benchmark::State& state) { insert_benchmark(state, true, false, true); }

void BM_ScanToPolygon(benchmark::State& state) {
  std::mt19937_64 rng(1);
  const auto walls = testing::rock_field(30, 30, kSpacingM, rng);
  const Pose2 pose{10.0, 10.0, 0.3};
  const auto ranges = testing::cast_scan(walls, pose, kSpec);
  const auto o = scan_options();
  for (auto _ : state) {
    auto r = scan_to_polygon(ranges, kSpec.angle_min, kSpec.angle_increment, pose, o);
    benchmark::DoNotOptimize(r);
  }
}

void BM_MergePlanningMap(benchmark::State& state) {
  Fixture& f = fixture(static_cast<std::size_t>(state.range(0)), true);
  for (auto _ : state) {
    auto merged = f.map.planning_map();
    benchmark::DoNotOptimize(merged);
  }
}

BENCHMARK(BM_ScanToPolygon)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InsertTyped)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond)
    ->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_InsertPlain)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond)
    ->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_InsertTypedThenPlanning)->Arg(1000)->Unit(benchmark::kMillisecond)
    ->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_InsertIntel)->Arg(1000)->Arg(5000)->Unit(benchmark::kMillisecond)
    ->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_MergePlanningMap)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  pex::bench::MedianCollector reporter;
  reporter.run(&argc, argv);
  auto get = [&](const std::string& name) { return reporter.median(name); };
  const double insert_1k = get("BM_InsertTyped/1000"), plain_1k = get("BM_InsertPlain/1000");
  // Memory: the 10k map's bytes over the vertices it stores (free, obstacle
  // and planning layers), and a 5 cm grid (1 byte a cell) over the explored
  // area's bounding tiles against the polygon map's bytes.
  Fixture& f = fixture(10000, true);
  std::size_t stored_vertices = 0;
  for (const auto& [key, tile] : f.map.tiles())
    stored_vertices += vertex_count(tile->free) + vertex_count(tile->obstacles) + vertex_count(tile->planning());
  const double bytes = static_cast<double>(f.map.memory_bytes());
  const double explored_area_m2 = f.map.free_area_m2();  // the timed scans are not in the map
  const double grid_bytes = explored_area_m2 / (0.05 * 0.05);
  std::printf("# 10k map: %zu tiles, %.0f bytes, %zu stored vertices, explored %.0f m2, grid %.0f bytes\n",
              f.map.tile_count(), bytes, stored_vertices, explored_area_m2, grid_bytes);
  std::printf(
      "{\"insert_ms_1k\":%.4f,\"insert_ms_10k\":%.4f,\"insert_ms_100k\":%.4f,\"plain_union_ms_1k\":%.4f,"
      "\"reassign_share_1k\":%.3f,\"bytes_per_vertex\":%.1f,\"grid_over_polygon_bytes\":%.2f,"
      "\"insert_ms_1k_intel\":%.4f}\n",
      insert_1k, get("BM_InsertTyped/10000"), get("BM_InsertTyped/100000"), plain_1k,
      plain_1k > 0 ? (insert_1k - plain_1k) / plain_1k : -1.0,
      stored_vertices ? bytes / static_cast<double>(stored_vertices) : -1.0,
      bytes > 0 ? grid_bytes / bytes : -1.0, get("BM_InsertIntel/1000"));
  return 0;
}
