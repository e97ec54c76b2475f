// Counts the polygon map's failures over many inserts (issue 16's targets:
// failed tile updates and merge failures all 0, every merged map valid; no
// overlay is redone with Boost since issue 16, so there is no fallback to count). Not a test (it runs minutes): the figures go to docs/mapping.md.
//
//   pex-stress-mapping --random N          N random noisy scans of a room with
//                                           pillars into one map (the property
//                                           test's generator, at any count)
//   pex-stress-mapping --intel FILE [--maps M]
//                                           every scan of a CARMEN log after
//                                           0.2 m / 0.25 rad of motion, into M
//                                           maps at the logged pose perturbed
//                                           by a seeded few cm / 1 degree
//                                           (like SLAM's particle maps)
//   --merge-every K    merge both layers every K inserts and check them with
//                      bg::is_valid (default 200)
//   --merge-epsilon E  merge with this RDP tolerance (default: the map's)
//   --verbose 1        print every merge's outcome and the reason of every
//                      tile whose planning layer failed
//   --dump FILE        (--intel) write the layers of the first map's tiles
//                      whose planning layer failed, and its merged planning
//                      map, as WKT
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "carmen_scans.hpp"
#include "cli/command_line.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"
#include "mapping/test_support.hpp"

using namespace pex::mapping;
using pex::geometry::Pose2;

namespace {

struct Counts {
  long scans = 0, inserted = 0, failed_tiles = 0, merges = 0, merge_failures = 0, merge_invalid = 0,
       stale_planning = 0;
  std::string first_error;
};

// Options that only change what is merged or printed.
std::optional<double> g_merge_epsilon;
bool g_verbose = false;
std::string g_dump;

void merge_and_check(const PolygonMap& map, Counts& c) {
  for (const bool planning : {false, true}) {
    const MergeResult merged = planning ? map.planning_map(g_merge_epsilon) : map.free_space(g_merge_epsilon);
    ++c.merges;
    c.stale_planning += merged.stale_planning_tiles;
    if (g_verbose) {
      std::printf("merge %s ok %d error %s\n", planning ? "planning" : "free", merged.ok, merged.error.c_str());
      if (planning)
        for (const auto& [key, tile] : map.tiles())
          if (tile->planning_failed()) std::printf("  tile %d,%d: %s\n", key.first, key.second, tile->planning_error().c_str());
    }
    if (!merged.ok) {
      ++c.merge_failures;
      if (c.first_error.empty()) c.first_error = "merge: " + merged.error;
      continue;
    }
    std::string why;
    if (!bg::is_valid(geometry_of(merged.polygons), why)) {
      ++c.merge_invalid;
      if (c.first_error.empty()) c.first_error = "merged map invalid: " + why;
    }
  }
}

void insert(PolygonMap& map, const TypedPolygon& scan, Counts& c) {
  ++c.inserted;
  const InsertResult r = map.insert(scan);
  if (!r.ok && c.first_error.empty()) c.first_error = "insert: " + r.error;
}

void print(const Counts& c, const std::vector<PolygonMap>& maps) {
  long failed = 0;
  for (const auto& m : maps) failed += m.failed_tile_updates();
  std::printf(
      "{\"scans\":%ld,\"inserts\":%ld,\"failed_tile_updates\":%ld,\"merges\":%ld,"
      "\"merge_failures\":%ld,\"merged_invalid\":%ld,\"stale_planning_tiles\":%ld}\n",
      c.scans, c.inserted, failed, c.merges, c.merge_failures, c.merge_invalid, c.stale_planning);
  if (!c.first_error.empty()) std::printf("first error: %s\n", c.first_error.c_str());
}

int run_random(long n, long merge_every) {
  std::mt19937_64 rng(31337);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto walls = testing::random_room(30, 20, 25, rng);
  std::vector<PolygonMap> maps(1);
  Counts c;
  const testing::ScanSpec spec;
  for (long k = 0; k < n; ++k) {
    const Pose2 pose{1 + 28 * u(rng), 1 + 18 * u(rng), 6.28 * u(rng)};
    ScanPolygonOptions options;
    options.free_range_m = 1.0 + 4.0 * u(rng);
    options.range_max_m = spec.range_max_m;
    const double noise = 0.03 * u(rng);
    const auto scan = scan_to_polygon(testing::cast_scan(walls, pose, spec, noise, &rng), spec.angle_min,
                                      spec.angle_increment, pose, options);
    ++c.scans;
    if (!scan.ok) continue;
    insert(maps[0], scan.polygon, c);
    if ((k + 1) % merge_every == 0) merge_and_check(maps[0], c);
    if ((k + 1) % 10000 == 0) print(c, maps);
  }
  merge_and_check(maps[0], c);
  print(c, maps);
  return 0;
}

int run_log(const std::string& path, int map_count, long merge_every) {
  std::vector<PolygonMap> maps(static_cast<std::size_t>(map_count));
  std::mt19937_64 rng(7);
  std::normal_distribution<double> shift(0.0, 0.03), turn(0.0, 0.017);
  const ScanPolygonOptions options;
  Counts c;
  const bool read = pex::bench::for_each_moved_scan(path, [&](const std::vector<float>& ranges, const auto& laser,
                                                              const Pose2& pose) {
    ++c.scans;
    for (std::size_t m = 0; m < maps.size(); ++m) {
      Pose2 p = pose;
      if (m > 0) {  // the other maps: the pose as a particle might have it
        p.x_m += shift(rng);
        p.y_m += shift(rng);
        p.theta_rad += turn(rng);
      }
      const auto scan = scan_to_polygon(ranges, laser.angle_min_rad, laser.angle_increment_rad, p, options);
      if (scan.ok) insert(maps[m], scan.polygon, c);
    }
    if (c.scans % merge_every == 0) merge_and_check(maps[0], c);
    return true;
  });
  if (!read) {
    std::fprintf(stderr, "cannot read %s\n", path.c_str());
    return 2;
  }
  merge_and_check(maps[0], c);
  print(c, maps);
  if (!g_dump.empty()) {
    std::ofstream out(g_dump);
    out.precision(17);
    for (const auto& [key, tile] : maps[0].tiles()) {
      if (!tile->planning_failed()) continue;
      out << "tile " << key.first << " " << key.second << "\nfree " << bg::wkt(geometry_of(tile->free))
          << "\nobstacles " << bg::wkt(geometry_of(tile->obstacles)) << "\nplanning "
          << bg::wkt(geometry_of(tile->planning())) << "\n";
    }
    const auto merged = maps[0].planning_map();
    out << "merged " << bg::wkt(geometry_of(merged.polygons)) << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  long random = 0, merge_every = 200;
  int map_count = 1;
  std::string log;
  CLI::App app{"Count the polygon map's failures over many inserts (docs/mapping.md)", "pex-stress-mapping"};
  app.add_option("--random", random, "N random noisy scans of a room with pillars into one map");
  app.add_option("--intel", log, "every scan of this CARMEN log after 0.2 m / 0.25 rad of motion");
  app.add_option("--maps", map_count, "(--intel) into this many maps at perturbed poses")->check(CLI::PositiveNumber);
  app.add_option("--merge-every", merge_every, "merge both layers every K inserts and check them")
      ->check(CLI::PositiveNumber);
  double merge_epsilon = -1.0;
  app.add_option("--merge-epsilon", merge_epsilon, "merge with this RDP tolerance (default: the map's)");
  int verbose = 0;
  app.add_option("--verbose", verbose, "1: every merge's outcome and every failed planning layer's reason");
  app.add_option("--dump", g_dump, "(--intel) write the failed tiles' layers and the merged map to this file");
  if (const auto code = pex::cli::parse_command_line(app, "pex-stress-mapping", argc, argv)) return *code;
  g_verbose = verbose == 1;
  if (merge_epsilon >= 0.0) g_merge_epsilon = merge_epsilon;
  if (random <= 0 && log.empty()) {
    std::fprintf(stderr, "pex-stress-mapping: give --random N or --intel FILE (--help)\n");
    return 64;
  }
  return random > 0 ? run_random(random, merge_every) : run_log(log, map_count, merge_every);
}
