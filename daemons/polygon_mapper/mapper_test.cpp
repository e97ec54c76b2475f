#include "mapper.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include <gtest/gtest.h>

#include "mapping/test_support.hpp"
#include "runtime/config.hpp"
#include "runtime/daemon.hpp"

namespace pex::polygon_mapper {
namespace {

TEST(PoseBuffer, InterpolatesAndWrapsTheta) {
  PoseBuffer buffer(10.0);
  ASSERT_TRUE(buffer.add({1'000'000, {0.0, 0.0, 3.0}}));
  ASSERT_TRUE(buffer.add({2'000'000, {2.0, 1.0, -3.0}}));  // turned 0.28 rad through pi
  geometry::Pose2 p;
  ASSERT_EQ(buffer.pose_at(1'500'000, 2'000'000, p), PoseBuffer::Lookup::kOk);
  EXPECT_NEAR(p.x_m, 1.0, 1e-12);
  EXPECT_NEAR(p.y_m, 0.5, 1e-12);
  EXPECT_NEAR(std::abs(p.theta_rad), std::numbers::pi, 1e-9);
  EXPECT_EQ(buffer.pose_at(500'000, 2'000'000, p), PoseBuffer::Lookup::kTooOld);
  EXPECT_EQ(buffer.pose_at(2'500'000, 2'000'000, p), PoseBuffer::Lookup::kTooNew);
  EXPECT_EQ(buffer.pose_at(1'500'000, 100'000, p), PoseBuffer::Lookup::kGap);
  EXPECT_FALSE(buffer.add({3'000'000, {std::nan(""), 0.0, 0.0}}));
  EXPECT_FALSE(buffer.add({1'500'000, {0.0, 0.0, 0.0}}));  // out of order
}

pex::laser_scan_t make_scan(const std::vector<mapping::testing::Wall>& walls, const geometry::Pose2& pose,
                            std::int64_t utime) {
  const mapping::testing::ScanSpec spec;
  pex::laser_scan_t scan{};
  scan.utime = utime;
  scan.angle_min = static_cast<float>(spec.angle_min);
  scan.angle_increment = static_cast<float>(spec.angle_increment);
  scan.range_min = 0.05f;
  scan.range_max = static_cast<float>(spec.range_max_m);
  scan.ranges = mapping::testing::cast_scan(walls, pose, spec);
  scan.nranges = static_cast<std::int32_t>(scan.ranges.size());
  return scan;
}

TEST(Mapper, ScansPairedWithInterpolatedPosesBuildTheRoom) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 10, 5);
  Mapper mapper(MapperOptions{});
  // The robot drives along y = 2.5 at 1 m/s; poses at 10 Hz, scans at 5 Hz
  // in between the poses (paired by interpolation).
  for (int k = 0; k <= 80; ++k) {
    const std::int64_t t = 1'000'000 + k * 100'000;
    mapper.on_pose({t, {1.0 + 0.1 * k, 2.5, 0.0}});
    if (k % 2 == 1 && k < 80) {
      const std::int64_t ts = t + 50'000;
      mapper.on_scan(make_scan(walls, {1.0 + 0.1 * k + 0.05, 2.5, 0.0}, ts));
    }
  }
  EXPECT_GT(mapper.counters().scans_inserted, 10);
  EXPECT_GT(mapper.counters().scans_skipped_no_motion, 10);
  const auto msg = mapper.map_message(99);
  ASSERT_TRUE(msg.has_value());
  EXPECT_EQ(msg->utime, 99);
  EXPECT_EQ(msg->nrings, static_cast<int>(msg->rings.size()));
  EXPECT_GT(msg->free_area_m2, 0.8 * 50.0);
  EXPECT_LE(msg->free_area_m2, 50.0);
  EXPECT_GT(msg->obstacle_length_m, 20.0);
  int vertices = 0;
  for (const auto& r : msg->rings) {
    EXPECT_EQ(r.nvertices, static_cast<int>(r.x.size()));
    EXPECT_EQ(r.x.size(), r.edge_type.size());
    vertices += r.nvertices;
  }
  EXPECT_EQ(vertices, msg->vertex_count);
  EXPECT_NEAR(msg->robot_x, 1.0 + 0.1 * 79 + 0.05, 0.25);
}

// A thin wall (no thickness, as the simulator's) splits a 10 x 5 m box into
// two rooms joined by a door; the robot looks at it from both sides. MAP is
// the free space minus the obstacle band, which reaches obstacle_outer_m past
// the wall into the other room's floor; MAP_FREE is the free space the scans
// saw, floor right up to the wall on both sides.
TEST(Mapper, FreeSpaceMessageKeepsTheFloorTheObstacleBandTakes) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 10, 5);
  walls.push_back({mapping::Point{5.0, 0.0}, mapping::Point{5.0, 3.0}});  // the thin wall, door from y = 3 to 5
  Mapper mapper(MapperOptions{});
  const std::vector<geometry::Pose2> stops{{2.5, 1.5, 0.0}, {2.5, 4.0, 0.0}, {7.5, 1.5, 3.14}, {7.5, 4.0, 3.14}};
  std::int64_t t = 1'000'000;
  for (const auto& stop : stops) {
    mapper.on_pose({t, stop});
    mapper.on_scan(make_scan(walls, stop, t + 10'000));
    mapper.on_pose({t + 20'000, stop});
    t += 2'000'000;  // > insert_max_interval_s: every stop goes in
  }
  ASSERT_EQ(mapper.counters().scans_inserted, 4);
  const auto planning = mapper.map_message(t);
  const auto free = mapper.free_space_message(t);
  ASSERT_TRUE(planning && free);
  EXPECT_EQ(free->utime, t);
  EXPECT_EQ(free->scans_inserted, 4);
  EXPECT_LE(free->free_area_m2, 50.0 + 1e-6);
  // The band takes at least obstacle_outer_m along each side of the 3 m wall
  // (and more along the box): the free space has it back.
  const double band = MapperOptions{}.map.obstacle_outer_m;
  EXPECT_GT(free->free_area_m2, planning->free_area_m2 + 2 * 3.0 * band);
  EXPECT_GT(free->free_area_m2, 0.97 * 50.0);
  EXPECT_GT(free->obstacle_length_m, 20.0);
  // Cached until the map changes; a new insert makes both new.
  EXPECT_EQ(mapper.free_space_message(t + 1)->free_area_m2, free->free_area_m2);
}

TEST(Mapper, MalformedScansAreRefusedAndTheMapKept) {
  Mapper mapper(MapperOptions{});
  pex::laser_scan_t scan{};
  scan.angle_increment = 0.01f;
  scan.range_max = 10.0f;
  scan.ranges = {1.0f, 1.0f, 1.0f};
  scan.nranges = 2;  // disagrees with the array
  EXPECT_THROW(mapper.on_scan(scan), std::invalid_argument);
  scan.nranges = 3;
  scan.angle_increment = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(mapper.on_scan(scan), std::invalid_argument);
  scan.angle_increment = 0.01f;
  scan.nintensities = 2;
  scan.intensities = {1.0f, 2.0f};
  EXPECT_THROW(mapper.on_scan(scan), std::invalid_argument);
  EXPECT_EQ(mapper.counters().scans_received, 0);
  EXPECT_FALSE(mapper.map_message(0).has_value());
}

// The room seen from `at` (a scan at 1.01 s), then `second` (its utime
// 3.01 s) taken from `second_at`, each with poses around it.
void map_room_then(Mapper& mapper, const std::vector<mapping::testing::Wall>& walls, const geometry::Pose2& at,
                   const geometry::Pose2& second_at, const pex::laser_scan_t& second) {
  mapper.on_pose({1'000'000, at});
  mapper.on_scan(make_scan(walls, at, 1'010'000));
  mapper.on_pose({1'020'000, at});
  mapper.on_pose({3'000'000, second_at});
  mapper.on_scan(second);
  mapper.on_pose({3'020'000, second_at});
}

// A laser covered or dazzled answers "no echo" on every beam. Mapped, each
// such beam would be free space for free_range_m through the room's walls;
// with min_returns the scan is refused and the room is what it was.
TEST(Mapper, AScanWithoutReturnsIsRefusedAndTheWallsKept) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 4, 3);
  MapperOptions options;
  options.scan.min_returns = 5;
  Mapper mapper(options);
  const geometry::Pose2 at{2.0, 1.5, 0.0};
  mapper.on_pose({1'000'000, at});
  mapper.on_scan(make_scan(walls, at, 1'010'000));
  mapper.on_pose({1'020'000, at});
  ASSERT_EQ(mapper.counters().scans_inserted, 1);
  const double room_m2 = mapper.free_space_message(2'000'000)->free_area_m2;
  EXPECT_LE(room_m2, 12.0 + 1e-6);
  auto blind = make_scan(walls, {2.0, 1.5, 1.0}, 3'010'000);
  for (auto& r : blind.ranges) r = 0.0f;  // no echo (the reader's NaN is the same)
  blind.ranges[7] = 1.0f;                 // four returns are not a view either
  blind.ranges[8] = 1.0f;
  blind.ranges[9] = 1.0f;
  blind.ranges[10] = 1.0f;
  mapper.on_pose({3'000'000, {2.0, 1.5, 1.0}});
  EXPECT_THROW(mapper.on_scan(blind), std::invalid_argument);
  mapper.on_pose({3'020'000, {2.0, 1.5, 1.0}});
  EXPECT_EQ(mapper.counters().scans_inserted, 1);
  EXPECT_EQ(mapper.free_space_message(4'000'000)->free_area_m2, room_m2);
  // Without the check (and without stopping beams at the walls the map
  // holds) the same scan goes in and clears the walls around.
  MapperOptions unchecked_options;
  unchecked_options.scan.no_return_stops_at_walls = false;
  Mapper unchecked(unchecked_options);
  map_room_then(unchecked, walls, at, {2.0, 1.5, 1.0}, blind);
  EXPECT_EQ(unchecked.counters().scans_inserted, 2);
  EXPECT_GT(unchecked.free_space_message(4'000'000)->free_area_m2, 12.0 + 1.0);
}

// Part of the window covered: the beams of a sector have no echo, the rest
// see. The scan has returns enough to go in; its blind beams stop at the
// walls the map holds, so the room stays the room, and they are counted.
TEST(Mapper, ABlindSectorsBeamsStopAtTheWallsTheMapHolds) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 4, 3);
  const geometry::Pose2 at{2.0, 1.5, 0.0};
  auto blind = make_scan(walls, {2.5, 1.5, 0.5}, 3'010'000);
  for (std::size_t i = 0; i < blind.ranges.size(); ++i) {
    const double a = blind.angle_min + blind.angle_increment * static_cast<double>(i);
    if (a > -0.6 && a < 0.6) blind.ranges[i] = 0.0f;
  }
  auto area_after_blind_scan = [&](bool stop_at_walls, std::int64_t* stopped) {
    MapperOptions options;
    options.scan.min_returns = 5;
    options.scan.no_return_stops_at_walls = stop_at_walls;
    Mapper mapper(options);
    map_room_then(mapper, walls, at, {2.5, 1.5, 0.5}, blind);
    EXPECT_EQ(mapper.counters().scans_inserted, 2);
    *stopped = mapper.counters().no_return_beams_stopped;
    return mapper.free_space_message(4'000'000)->free_area_m2;
  };
  std::int64_t stopped = 0, stopped_off = 0;
  EXPECT_LE(area_after_blind_scan(true, &stopped), 12.0 + 1e-6);
  EXPECT_GT(stopped, 50);
  EXPECT_GT(area_after_blind_scan(false, &stopped_off), 12.0 + 1.0) << "the blind sector carves the walls away";
  EXPECT_EQ(stopped_off, 0);
}

// The same sector blind scan after scan: after two inserted scans with its
// beams stopped at the room's walls the mapper counts them blind (once an
// onset), and one scan that sees again clears them.
TEST(Mapper, ASectorBlindScanAfterScanIsCountedBlindUntilItSeesAgain) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 4, 3);
  Mapper mapper(MapperOptions{});
  const geometry::Pose2 at{2.0, 1.5, 0.0};
  auto scan_at = [&](std::int64_t utime, bool blind) {
    auto scan = make_scan(walls, at, utime);
    for (std::size_t i = 0; i < scan.ranges.size() && blind; ++i) {
      const double a = scan.angle_min + scan.angle_increment * static_cast<double>(i);
      if (a > -0.6 && a < 0.6) scan.ranges[i] = 0.0f;
    }
    mapper.on_pose({utime - 10'000, at});
    mapper.on_scan(scan);
    mapper.on_pose({utime + 10'000, at});
  };
  scan_at(1'010'000, false);
  // Standing still, a scan goes in every insert_max_interval_s (1 s).
  scan_at(2'510'000, true);
  EXPECT_EQ(mapper.blind_beams().count(), 0);
  scan_at(4'010'000, true);
  ASSERT_EQ(mapper.counters().scans_inserted, 3);
  EXPECT_GT(mapper.blind_beams().count(), 100);  // 1.2 rad of 0.5-degree beams: 137
  EXPECT_EQ(mapper.blind_beams().onsets(), 1);
  // Said (DEGRADED) once blind for blind_degraded_after_s (5 s) of scan time:
  // glass blinds a beam or two for a moment.
  EXPECT_EQ(mapper.blind_laser_reason(), "");
  scan_at(7'010'000, true);
  EXPECT_EQ(mapper.blind_laser_reason(), "") << "blind for 3 s";
  scan_at(9'010'000, true);
  // The DEGRADED reason says where: one sector, about -0.6..0.6 rad.
  const std::string reason = mapper.blind_laser_reason();
  int beams = 0;
  double from_rad = 0.0, to_rad = 0.0;
  char after = 0;
  ASSERT_EQ(std::sscanf(reason.c_str(), "laser blind on %d beams at %lf..%lf rad%c", &beams, &from_rad, &to_rad, &after),
            4)
      << reason;
  EXPECT_EQ(beams, mapper.blind_beams().count());
  EXPECT_NEAR(from_rad, -0.6, 0.015) << reason;  // the first beam above -0.6, to 2 decimals
  EXPECT_NEAR(to_rad, 0.6, 0.015) << reason;
  EXPECT_EQ(after, ' ') << "one sector only: " << reason;
  scan_at(10'510'000, false);
  EXPECT_EQ(mapper.blind_beams().count(), 0);
  EXPECT_EQ(mapper.blind_laser_reason(), "");
  EXPECT_EQ(mapper.blind_beams().onsets(), 1);
  EXPECT_LE(mapper.free_space_message(11'000'000)->free_area_m2, 12.0 + 1e-6);
}

TEST(Mapper, ScanNewerThanEveryPoseWaitsForOne) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 10, 5);
  Mapper mapper(MapperOptions{});
  mapper.on_pose({1'000'000, {2.0, 2.5, 0.0}});
  mapper.on_scan(make_scan(walls, {2.0, 2.5, 0.0}, 1'050'000));
  EXPECT_EQ(mapper.counters().scans_inserted, 0);
  mapper.on_pose({1'100'000, {2.0, 2.5, 0.0}});
  EXPECT_EQ(mapper.counters().scans_inserted, 1);
}

TEST(MapperOptions, ShippedConfigLoadsAndNamesTheSlamSource) {
  auto config = runtime::ConfigReader::from_file(std::string(PEX_SOURCE_DIR) + "/config/polygon_mapper.toml");
  const auto options = load_options(config);
  runtime::load_runtime_options(config);  // heartbeat_period_ms and clock: read by run_daemon
  EXPECT_NO_THROW(config.finish());
  EXPECT_EQ(options.pose_source, "slam");
  for (const char* text : {"pose_source = \"gps\"\n", "[map]\ntile_origin_m = 1e300\n"}) {
    auto bogus = runtime::ConfigReader::from_string(text, "test");
    EXPECT_THROW(load_options(bogus), runtime::ConfigError) << text;
  }
}

// --- pose_source = "slam": one map per particle, best particle's map published.

// Ranges seen from `pose` inside the room [0, 20] x [0, 10]: 181 beams over 180 degrees.
pex::laser_scan_t room_scan(std::int64_t utime, const geometry::Pose2& pose) {
  pex::laser_scan_t s{};
  s.utime = utime;
  s.angle_min = static_cast<float>(-M_PI / 2);
  s.angle_increment = static_cast<float>(M_PI / 180);
  s.range_min = 0.05f;
  s.range_max = 30.0f;
  for (int i = 0; i <= 180; ++i) {
    const double a = pose.theta_rad - M_PI / 2 + i * M_PI / 180, dx = std::cos(a), dy = std::sin(a);
    double t = 1e9;
    if (dx > 1e-12) t = std::min(t, (20 - pose.x_m) / dx);
    if (dx < -1e-12) t = std::min(t, -pose.x_m / dx);
    if (dy > 1e-12) t = std::min(t, (10 - pose.y_m) / dy);
    if (dy < -1e-12) t = std::min(t, -pose.y_m / dy);
    s.ranges.push_back(static_cast<float>(t));
  }
  s.nranges = static_cast<std::int32_t>(s.ranges.size());
  return s;
}

pex::slam_update_t slam_update(std::int64_t generation, std::int64_t scan_utime, int best,
                               const std::vector<std::pair<geometry::Pose2, int>>& particles) {
  pex::slam_update_t u{};
  u.utime = scan_utime + 1000;
  u.scan_utime = scan_utime;
  u.generation = generation;
  u.best = best;
  for (const auto& [pose, parent] : particles) {
    pex::particle_t p{};
    p.x = pose.x_m;
    p.y = pose.y_m;
    p.theta = pose.theta_rad;
    p.parent = parent;
    u.particles.push_back(p);
  }
  u.nparticles = static_cast<std::int32_t>(u.particles.size());
  return u;
}

MapperOptions slam_options() {
  MapperOptions o;
  o.pose_source = "slam";
  return o;
}

TEST(MapperSlam, BestParticleSwitchPublishesTheNewBestMapBuiltAlongItsTrajectory) {
  Mapper mapper(slam_options());
  // The robot drives along y = 5; particle 1 believes it drives along y = 5.6
  // (its map is shifted). Particle 0 is best until the last update.
  const std::vector<double> xs = {4.0, 6.0, 8.0};
  std::vector<pex::laser_scan_t> scans;
  for (std::size_t g = 0; g < xs.size(); ++g) {
    scans.push_back(room_scan(1'000'000 * static_cast<std::int64_t>(g + 1), {xs[g], 5.0, 0.0}));
    mapper.on_scan(scans.back());
    const int parent = g == 0 ? -1 : 0;
    const bool last = g + 1 == xs.size();
    const bool switched = mapper.on_slam_update(slam_update(
        static_cast<std::int64_t>(g), scans.back().utime, last ? 1 : 0,
        {{{xs[g], 5.0, 0.0}, parent}, {{xs[g], 5.6, 0.0}, g == 0 ? -1 : 1}}));
    EXPECT_EQ(switched, last) << g;
    auto msg = mapper.map_message(scans.back().utime + 2000);
    ASSERT_TRUE(msg.has_value());
    EXPECT_EQ(msg->particle, last ? 1 : 0);
    EXPECT_EQ(msg->generation, static_cast<std::int64_t>(g));
  }
  EXPECT_EQ(mapper.counters().best_switches, 1);
  EXPECT_EQ(mapper.counters().slam_updates, 3);

  // The published map equals a map built from scratch along particle 1's
  // trajectory (scan polygon and band built in the sensor frame and moved, as
  // the particle maps do).
  mapping::PolygonMap oracle(slam_options().map);
  for (std::size_t g = 0; g < xs.size(); ++g) {
    const auto poly = mapping::scan_to_polygon(scans[g].ranges, scans[g].angle_min, scans[g].angle_increment,
                                               {}, mapping::ScanPolygonOptions{});
    ASSERT_TRUE(poly.ok);
    oracle.insert(particle_maps::transformed(mapping::prepare_scan(poly.polygon, oracle.options()),
                                             {xs[g], 5.6, 0.0}));
  }
  const auto expected = oracle.planning_map();
  ASSERT_TRUE(expected.ok);
  const auto msg = mapper.map_message(10'000'000);
  ASSERT_TRUE(msg.has_value());
  EXPECT_NEAR(msg->free_area_m2, mapping::area(expected.polygons), 1e-9);
  EXPECT_EQ(msg->vertex_count, static_cast<std::int32_t>(mapping::vertex_count(expected.polygons)));
  // And it lies where particle 1 saw the room: shifted up by 0.6 m, so its top
  // reaches y = 10.6 - a little (obstacle band), well above the true wall at 10.
  double max_y = -1e9;
  for (const auto& ring : msg->rings)
    for (double y : ring.y) max_y = std::max(max_y, y);
  EXPECT_GT(max_y, 10.3);
  EXPECT_DOUBLE_EQ(msg->robot_y, 5.6);
}

TEST(MapperSlam, AnUpdateBeforeItsScanWaitsForTheScan) {
  Mapper mapper(slam_options());
  const auto scan = room_scan(5'000'000, {5, 5, 0});
  EXPECT_FALSE(mapper.on_slam_update(slam_update(0, scan.utime, 0, {{{5, 5, 0}, -1}})));
  EXPECT_EQ(mapper.counters().slam_updates, 0);
  mapper.on_scan(scan);
  EXPECT_EQ(mapper.counters().slam_updates, 1);
  EXPECT_TRUE(mapper.map_message(6'000'000).has_value());
}

TEST(MapperSlam, MalformedUpdatesAreRefusedAndTheMapsKept) {
  Mapper mapper(slam_options());
  const auto scan = room_scan(1'000'000, {5, 5, 0});
  mapper.on_scan(scan);
  mapper.on_slam_update(slam_update(0, scan.utime, 0, {{{5, 5, 0}, -1}, {{5, 5.1, 0}, -1}}));
  const double area = mapper.map().free_area_m2();
  auto bad = slam_update(1, scan.utime, 5, {{{5, 5, 0}, 0}});  // best out of range
  EXPECT_THROW(mapper.on_slam_update(bad), std::invalid_argument);
  bad = slam_update(1, scan.utime, 0, {{{5, 5, 0}, 0}});
  bad.nparticles = 3;  // disagrees with the array
  EXPECT_THROW(mapper.on_slam_update(bad), std::invalid_argument);
  const auto scan2 = room_scan(2'000'000, {6, 5, 0});
  mapper.on_scan(scan2);
  EXPECT_THROW(mapper.on_slam_update(slam_update(1, scan2.utime, 0, {{{6, 5, 0}, 7}})), std::invalid_argument);
  EXPECT_EQ(mapper.particle_maps().size(), 2u);
  EXPECT_EQ(mapper.map().free_area_m2(), area);
  // A good update after the refused ones still goes in.
  const auto scan3 = room_scan(3'000'000, {7, 5, 0});
  mapper.on_scan(scan3);
  mapper.on_slam_update(slam_update(1, scan3.utime, 0, {{{7, 5, 0}, 0}, {{7, 5.1, 0}, 1}}));
  EXPECT_EQ(mapper.counters().slam_updates, 2);
  EXPECT_GT(mapper.map().free_area_m2(), area);
}

// Two particles driving along y = 5 (particle 1 believes y = 5.3), one update
// per scan, epoch `epoch`, generations from `first_generation`.
void drive(Mapper& mapper, std::int64_t epoch, std::int64_t first_generation, const std::vector<double>& xs,
           std::int64_t first_utime) {
  for (std::size_t g = 0; g < xs.size(); ++g) {
    const auto scan = room_scan(first_utime + 1'000'000 * static_cast<std::int64_t>(g), {xs[g], 5.0, 0.0});
    mapper.on_scan(scan);
    const int parent0 = g == 0 && first_generation == 0 ? -1 : 0;
    const int parent1 = g == 0 && first_generation == 0 ? -1 : 1;
    auto u = slam_update(first_generation + static_cast<std::int64_t>(g), scan.utime, 0,
                         {{{xs[g], 5.0, 0.0}, parent0}, {{xs[g], 5.3, 0.0}, parent1}});
    u.epoch = epoch;
    mapper.on_slam_update(u);
  }
}

mapping::TypedMultiPolygon planning(const Mapper& mapper) {
  const auto merged = mapper.map().planning_map();
  EXPECT_TRUE(merged.ok) << merged.error;
  return merged.polygons;
}

// area(a - b): what `b` misses of `a`. The planning layer is derived anew
// after every insert (simplified, bands united), so slivers of rounding are
// not a loss; following the wrong parent loses metres.
constexpr double kSliver_m2 = 1e-3;
double area_missing(const mapping::TypedMultiPolygon& a, const mapping::TypedMultiPolygon& b) {
  mapping::MultiPolygon ga, gb, out;
  for (const auto& p : a) ga.push_back(p.geometry);
  for (const auto& p : b) gb.push_back(p.geometry);
  mapping::bg::difference(ga, gb, out);
  return mapping::bg::area(out);
}

TEST(MapperSlam, AMissedUpdateGoesOnFromTheBestMapInsteadOfFollowingParentsOfAnotherGeneration) {
  Mapper mapper(slam_options());
  drive(mapper, 77, 0, {2.0, 3.0}, 1'000'000);
  const auto before = planning(mapper);
  EXPECT_EQ(mapper.counters().slam_resyncs, 0);
  // Generation 2 is lost; generation 3 names parents in generation 2's set:
  // a resampling that made particle 0 a child of particle 1 (the shifted map).
  const auto scan = room_scan(9'000'000, {4.0, 5.0, 0.0});
  mapper.on_scan(scan);
  auto u = slam_update(3, scan.utime, 0, {{{4.0, 5.0, 0.0}, 1}, {{4.0, 5.3, 0.0}, 1}});
  u.epoch = 77;
  mapper.on_slam_update(u);
  EXPECT_EQ(mapper.counters().slam_resyncs, 1);
  EXPECT_EQ(mapper.counters().slam_epoch_changes, 0);
  // The map went on from the best map (particle 0's, at y = 5), not from
  // particle 1's shifted one: nothing of it is lost.
  EXPECT_LT(area_missing(before, planning(mapper)), kSliver_m2);
  // And the next update follows parents again.
  drive(mapper, 77, 4, {5.0}, 10'000'000);
  EXPECT_EQ(mapper.counters().slam_resyncs, 1);
  EXPECT_EQ(mapper.counters().slam_updates, 4);
}

TEST(MapperSlam, ARepublishedParticleSetContinuesTheMaps) {
  Mapper mapper(slam_options());
  drive(mapper, 77, 0, {2.0, 3.0}, 1'000'000);
  const auto scan = room_scan(5'000'000, {3.0, 5.0, 0.0});
  mapper.on_scan(scan);
  auto u = slam_update(1, scan.utime, 0, {{{3.0, 5.0, 0.0}, 0}, {{3.0, 5.3, 0.0}, 1}});
  u.epoch = 77;
  u.republished = true;
  mapper.on_slam_update(u);
  EXPECT_EQ(mapper.counters().slam_updates, 3);
  EXPECT_EQ(mapper.counters().slam_resyncs, 0);
}

TEST(MapperSlam, ASlamOfAnotherEpochStartsANewMapNeverMixedWithTheOld) {
  Mapper mapper(slam_options());
  drive(mapper, 77, 0, {2.0, 3.0, 4.0, 5.0}, 1'000'000);
  // A SLAM started afresh: its frame has the robot at the origin.
  drive(mapper, 88, 0, {0.5}, 10'000'000);
  EXPECT_EQ(mapper.counters().slam_epoch_changes, 1);
  EXPECT_EQ(mapper.counters().slam_resyncs, 0);
  // The map is the one scan of the new filter, nothing of the old.
  Mapper fresh(slam_options());
  drive(fresh, 88, 0, {0.5}, 10'000'000);
  EXPECT_DOUBLE_EQ(mapper.map().free_area_m2(), fresh.map().free_area_m2());
}

TEST(MapperSlam, ARestoredMapperPublishesTheSavedMapAndGoesOnFromItWithTheSameSlam) {
  Mapper mapper(slam_options());
  drive(mapper, 77, 0, {2.0, 4.0, 6.0}, 1'000'000);
  const std::string saved = mapper.checkpoint();
  const auto before = planning(mapper);

  Mapper restarted(slam_options());
  ASSERT_EQ(restarted.restore(saved), "");
  // Published at once, before any input: the map of before.
  const auto msg = restarted.map_message(20'000'000);
  ASSERT_TRUE(msg.has_value());
  EXPECT_DOUBLE_EQ(msg->free_area_m2, mapper.map_message(20'000'000)->free_area_m2);
  EXPECT_EQ(msg->vertex_count, mapper.map_message(20'000'000)->vertex_count);
  EXPECT_EQ(msg->scan_utime, mapper.map_message(20'000'000)->scan_utime);
  // SLAM (the same lineage) went on meanwhile: generation 7 follows 6, which
  // this mapper never saw.
  drive(restarted, 77, 7, {8.0, 10.0}, 30'000'000);
  EXPECT_EQ(restarted.counters().slam_resyncs, 1);
  EXPECT_LT(area_missing(before, planning(restarted)), kSliver_m2);
  // It is the map the mapper that never stopped makes of the same scans
  // (generations 3 and 4 for it), tile layer for tile layer.
  drive(mapper, 77, 3, {8.0, 10.0}, 30'000'000);
  EXPECT_EQ(mapper.counters().slam_resyncs, 0);
  EXPECT_EQ(restarted.map().free_area_m2(), mapper.map().free_area_m2());
  EXPECT_EQ(restarted.map().free_vertex_count(), mapper.map().free_vertex_count());
  EXPECT_EQ(restarted.map().planning_vertex_count(), mapper.map().planning_vertex_count());

  // The same checkpoint with a SLAM of another epoch: the saved map is in
  // another frame and is dropped.
  Mapper other(slam_options());
  ASSERT_EQ(other.restore(saved), "");
  drive(other, 88, 0, {8.0}, 30'000'000);
  EXPECT_EQ(other.counters().slam_epoch_changes, 1);
  EXPECT_GT(area_missing(before, planning(other)), 1.0);
}

TEST(Mapper, ACheckpointOfAnotherKindOrDamagedIsRefusedAndNothingChanges) {
  Mapper slam_mapper(slam_options());
  drive(slam_mapper, 77, 0, {2.0, 4.0}, 1'000'000);
  const std::string saved = slam_mapper.checkpoint();
  Mapper odometry_mapper(MapperOptions{});
  EXPECT_NE(odometry_mapper.restore(saved).find("pose_source"), std::string::npos);
  EXPECT_FALSE(odometry_mapper.map_message(1).has_value());
  Mapper damaged(slam_options());
  std::string broken = saved;
  broken[broken.size() / 2] ^= 0x01;
  EXPECT_NE(damaged.restore(broken).find("checksum"), std::string::npos);
  EXPECT_NE(damaged.restore(saved.substr(0, saved.size() / 2)).find("cut short"), std::string::npos);
  EXPECT_FALSE(damaged.map_message(1).has_value());
}

TEST(Mapper, AnOdometryMapperRestoresItsMapAndLastInsertPose) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 10, 5);
  MapperOptions options;
  options.insert_max_interval_s = 0.0;  // only motion inserts, so the restored last pose decides
  Mapper mapper(options);
  for (int k = 0; k <= 20; ++k) {
    const std::int64_t t = 1'000'000 + k * 100'000;
    mapper.on_pose({t, {1.0 + 0.1 * k, 2.5, 0.0}});
    if (k % 2 == 1 && k < 20) mapper.on_scan(make_scan(walls, {1.0 + 0.1 * k + 0.05, 2.5, 0.0}, t + 50'000));
  }
  Mapper restarted(options);
  ASSERT_EQ(restarted.restore(mapper.checkpoint()), "");
  EXPECT_EQ(restarted.map().free_area_m2(), mapper.map().free_area_m2());
  EXPECT_EQ(restarted.counters().scans_inserted, mapper.counters().scans_inserted);
  // The last insert pose came back too: a scan from the same place is skipped.
  const auto last = mapper.map_message(5'000'000);
  restarted.on_pose({10'000'000, {last->robot_x, last->robot_y, last->robot_theta}});
  restarted.on_pose({10'200'000, {last->robot_x, last->robot_y, last->robot_theta}});
  restarted.on_scan(make_scan(walls, {last->robot_x, last->robot_y, last->robot_theta}, 10'100'000));
  EXPECT_EQ(restarted.counters().scans_skipped_no_motion, 1);
}

}  // namespace
}  // namespace pex::polygon_mapper
