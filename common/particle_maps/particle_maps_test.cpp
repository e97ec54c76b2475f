#include "particle_maps/particle_maps.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using pex::geometry::Pose2;
using pex::particle_maps::ParticleMaps;
using pex::particle_maps::ParticleState;
using pex::particle_maps::SensorScan;

namespace {

// Ranges seen from `pose` inside the axis-aligned room [0, w] x [0, h]:
// 181 beams over 180 degrees, the distance to where each ray leaves the room.
std::vector<float> room_scan(const Pose2& pose, double w, double h) {
  std::vector<float> r;
  for (int i = 0; i <= 180; ++i) {
    const double a = pose.theta_rad - M_PI / 2 + i * M_PI / 180;
    const double dx = std::cos(a), dy = std::sin(a);
    double t = 1e9;
    if (dx > 1e-12) t = std::min(t, (w - pose.x_m) / dx);
    if (dx < -1e-12) t = std::min(t, -pose.x_m / dx);
    if (dy > 1e-12) t = std::min(t, (h - pose.y_m) / dy);
    if (dy < -1e-12) t = std::min(t, -pose.y_m / dy);
    r.push_back(static_cast<float>(t));
  }
  return r;
}

SensorScan scan_of(const std::vector<float>& ranges) {
  return SensorScan{ranges, -M_PI / 2, M_PI / 180, Pose2{}, {}};
}

pex::particle_maps::ParticleMapsOptions options() { return {}; }

pex::mapping::ScanPolygonOptions scan_options() {
  pex::mapping::ScanPolygonOptions o;
  o.range_max_m = 30.0;
  return o;
}

}  // namespace

TEST(ParticleMaps, TransformedMovesEveryVertexRigidly) {
  const auto ranges = room_scan({5, 5, 0}, 20, 10);
  const auto local = pex::mapping::scan_to_polygon(ranges, -M_PI / 2, M_PI / 180, Pose2{}, scan_options());
  ASSERT_TRUE(local.ok) << local.error;
  const Pose2 pose{3.0, -2.0, 0.7};
  const auto moved = pex::particle_maps::transformed(local.polygon, pose);
  EXPECT_NEAR(boost::geometry::area(moved.geometry), boost::geometry::area(local.polygon.geometry), 1e-9);
  // The same polygon as building it at that pose directly.
  const auto direct = pex::mapping::scan_to_polygon(ranges, -M_PI / 2, M_PI / 180, pose, scan_options());
  ASSERT_TRUE(direct.ok);
  ASSERT_EQ(direct.polygon.geometry.outer().size(), moved.geometry.outer().size());
  for (std::size_t i = 0; i < moved.geometry.outer().size(); ++i) {
    EXPECT_NEAR(moved.geometry.outer()[i].x(), direct.polygon.geometry.outer()[i].x(), 1e-9);
    EXPECT_NEAR(moved.geometry.outer()[i].y(), direct.polygon.geometry.outer()[i].y(), 1e-9);
  }
  EXPECT_EQ(moved.edge_types, local.polygon.edge_types);
}

TEST(ParticleMaps, EachMapEqualsTheMapBuiltAlongItsOwnAncestry) {
  // Three generations of 4 particles with resampling; each final map must equal a
  // map built from scratch by inserting the scans at the poses of its ancestors.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  ParticleMaps maps(options());
  std::vector<std::vector<Pose2>> ancestry(4);  // per particle: poses of its line so far
  std::vector<std::vector<float>> scans;
  const std::vector<std::vector<int>> parents = {{-1, -1, -1, -1}, {0, 0, 2, 3}, {1, 1, 1, 0}};
  for (int g = 0; g < 3; ++g) {
    const Pose2 truth{4.0 + 3.0 * g, 5.0, 0.2 * g};
    scans.push_back(room_scan(truth, 20, 10));
    std::vector<ParticleState> ps;
    std::vector<std::vector<Pose2>> next_ancestry;
    for (int i = 0; i < 4; ++i) {
      const Pose2 pose{truth.x_m + noise(rng), truth.y_m + noise(rng), truth.theta_rad + 0.1 * noise(rng)};
      ps.push_back({pose, parents[g][i]});
      auto line = g == 0 ? std::vector<Pose2>{} : ancestry[parents[g][i]];
      line.push_back(pose);
      next_ancestry.push_back(line);
    }
    ancestry = next_ancestry;
    const auto r = maps.update(ps, scan_of(scans.back()), scan_options());
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_TRUE(r.scan_inserted);
  }
  ASSERT_EQ(maps.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    pex::mapping::PolygonMap oracle(options().map);
    for (int g = 0; g < 3; ++g) {
      const auto local = pex::mapping::scan_to_polygon(scans[g], -M_PI / 2, M_PI / 180, Pose2{}, scan_options());
      oracle.insert(pex::particle_maps::transformed(local.polygon, ancestry[i][g]));
    }
    EXPECT_DOUBLE_EQ(maps.map(i).free_area_m2(), oracle.free_area_m2()) << i;
    EXPECT_EQ(maps.map(i).free_vertex_count(), oracle.free_vertex_count()) << i;
  }
  // Particles 0, 1, 2 descend from different lines than 3: their maps differ.
  EXPECT_NE(maps.map(0).free_area_m2(), maps.map(3).free_area_m2());
}

TEST(ParticleMaps, ChildrenShareTheTilesTheScanDidNotTouch) {
  ParticleMaps maps(options());
  // A long corridor: the first scan looks at its left end, the second at its
  // right end, so the two touch disjoint tiles.
  const Pose2 left_pose{10, 2, M_PI};
  const auto left = room_scan(left_pose, 80, 4);
  ASSERT_TRUE(maps.update({{left_pose, -1}}, scan_of(left), scan_options()).ok);
  const std::size_t tiles_left = maps.unique_tiles();
  const std::size_t bytes_left = maps.memory_bytes();
  const auto right = room_scan({70, 2, 0}, 80, 4);
  std::vector<ParticleState> children;
  for (int i = 0; i < 30; ++i) children.push_back({{70.0 + 0.01 * i, 2.0, 0.0}, 0});
  ASSERT_TRUE(maps.update(children, scan_of(right), scan_options()).ok);

  // Every child holds the left end through the very tiles its parent had.
  for (std::size_t i = 0; i < maps.size(); ++i) {
    std::size_t shared = 0;
    for (const auto& [key, tile] : maps.map(i).tiles())
      if (maps.map(0).tiles().count(key) && maps.map(0).tiles().at(key) == tile) ++shared;
    EXPECT_GE(shared, tiles_left) << i;
  }
  // So memory is the left end once plus 30 right ends, not 30 whole maps.
  ParticleMaps single(options());
  single.update({{left_pose, -1}}, scan_of(left), scan_options());
  single.update({{{70.0, 2.0, 0.0}, 0}}, scan_of(right), scan_options());
  const std::size_t one_map = single.memory_bytes();
  ASSERT_GT(one_map, bytes_left);
  // Tiles: the left end's once, each child's own right end.
  const std::size_t tiles_right = single.unique_tiles() - tiles_left;
  EXPECT_EQ(maps.unique_tiles(), tiles_left + 30 * tiles_right);
  // Bytes: sharing the left end saves about its size 29 times over.
  EXPECT_LT(maps.memory_bytes(), 30 * one_map - 29 * bytes_left / 2);
}

TEST(ParticleMaps, IdenticalChildrenInsertOnce) {
  ParticleMaps maps(options());
  const auto s = room_scan({5, 5, 0}, 20, 10);
  ASSERT_TRUE(maps.update({{{5, 5, 0}, -1}}, scan_of(s), scan_options()).ok);
  const auto r = maps.update({{{6, 5, 0}, 0}, {{6, 5, 0}, 0}, {{6, 5, 0.1}, 0}},
                             scan_of(room_scan({6, 5, 0}, 20, 10)), scan_options());
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.inserts, 2);
  EXPECT_EQ(maps.map(0).free_area_m2(), maps.map(1).free_area_m2());
}

TEST(ParticleMaps, BadParentsOrPosesChangeNothing) {
  ParticleMaps maps(options());
  const auto s = room_scan({5, 5, 0}, 20, 10);
  ASSERT_TRUE(maps.update({{{5, 5, 0}, -1}, {{5.1, 5, 0}, -1}}, scan_of(s), scan_options()).ok);
  const double area0 = maps.map(0).free_area_m2();
  auto r = maps.update({{{6, 5, 0}, 2}}, scan_of(s), scan_options());  // parent 2 of a generation of 2
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("parent 2"), std::string::npos) << r.error;
  r = maps.update({{{NAN, 5, 0}, 0}}, scan_of(s), scan_options());
  EXPECT_FALSE(r.ok);
  r = maps.update({}, scan_of(s), scan_options());
  EXPECT_FALSE(r.ok);
  ASSERT_EQ(maps.size(), 2u);
  EXPECT_EQ(maps.map(0).free_area_m2(), area0);
  EXPECT_EQ(maps.updates(), 1);
}

TEST(ParticleMaps, AScanWithoutPolygonStillAdvancesTheGeneration) {
  ParticleMaps maps(options());
  const auto s = room_scan({5, 5, 0}, 20, 10);
  ASSERT_TRUE(maps.update({{{5, 5, 0}, -1}}, scan_of(s), scan_options()).ok);
  const std::vector<float> none(181, std::numeric_limits<float>::quiet_NaN());
  const std::vector<float> empty;
  const auto r = maps.update({{{5, 5, 0}, 0}, {{5, 5, 0}, 0}}, scan_of(empty), scan_options());
  EXPECT_TRUE(r.ok);
  EXPECT_FALSE(r.scan_inserted);
  EXPECT_EQ(maps.size(), 2u);
  EXPECT_EQ(maps.map(1).free_area_m2(), maps.map(0).free_area_m2());
  (void)none;
}

TEST(ParticleMaps, ThreadCountDoesNotChangeTheMaps) {
  auto run = [](int threads) {
    auto o = options();
    o.threads = threads;
    ParticleMaps maps(o);
    std::vector<ParticleState> ps;
    for (int i = 0; i < 6; ++i) ps.push_back({{5.0 + 0.02 * i, 5.0, 0.01 * i}, -1});
    maps.update(ps, scan_of(room_scan({5, 5, 0}, 20, 10)), scan_options());
    for (auto& p : ps) {
      p.pose.x_m += 2.0;
      p.parent = static_cast<int>(&p - ps.data()) % 3;
    }
    maps.update(ps, scan_of(room_scan({7, 5, 0}, 20, 10)), scan_options());
    std::vector<std::pair<double, std::size_t>> out;
    for (std::size_t i = 0; i < maps.size(); ++i)
      out.emplace_back(maps.map(i).free_area_m2(), maps.map(i).free_vertex_count());
    return out;
  };
  EXPECT_EQ(run(1), run(3));
}

// Part of the window covered: each particle's blind beams stop at the walls
// of its own map, so no particle's room grows through them; with the stop
// off the same scan carves the walls away.
TEST(ParticleMaps, ABlindSectorsBeamsStopAtEachParticlesWalls) {
  auto run = [](bool stop_at_walls, std::vector<int>* stopped) {
    ParticleMaps maps(options());
    auto o = scan_options();
    o.no_return_stops_at_walls = stop_at_walls;
    // Both at the scans' true poses (the returns put the wall where it is),
    // two lines of descent, so the second scan goes into two maps.
    const std::vector<ParticleState> first{{{3.0, 2.0, 0.0}, -1}, {{3.0, 2.0, 0.0}, -1}};
    EXPECT_TRUE(maps.update(first, scan_of(room_scan({3.0, 2.0, 0.0}, 6, 4)), o).ok);
    auto blind = room_scan({3.2, 2.0, 0.1}, 6, 4);
    for (int i = 0; i <= 180; ++i)
      if (std::abs(-M_PI / 2 + i * M_PI / 180) < 0.5) blind[static_cast<std::size_t>(i)] = 0.0f;
    const std::vector<ParticleState> second{{{3.2, 2.0, 0.1}, 0}, {{3.2, 2.0, 0.1}, 1}};
    const auto r = maps.update(second, scan_of(blind), o);
    EXPECT_TRUE(r.ok && r.scan_inserted) << r.error;
    *stopped = r.no_return_beams_stopped;
    // How far the farther of the two maps reaches past the room's east wall (x = 6).
    double past = -1e9;
    for (std::size_t i = 0; i < 2; ++i) {
      const auto merged = maps.map(i).free_space();
      EXPECT_TRUE(merged.ok) << merged.error;
      for (const auto& p : merged.polygons)
        for (const auto& q : p.geometry.outer()) past = std::max(past, q.x() - 6.0);
    }
    return past;
  };
  std::vector<int> stopped, stopped_off;
  EXPECT_LE(run(true, &stopped), 0.01);
  ASSERT_EQ(stopped.size(), 2u);
  EXPECT_GT(stopped[0], 40);
  EXPECT_GT(stopped[1], 40);
  EXPECT_GT(run(false, &stopped_off), 0.5) << "the blind sector carves the wall away";
}

// Beams found blind (SensorScan::blind, mapping::BlindBeams' mask) give no
// free space in any particle's map, also where the map holds no wall to
// stop them: the room's west half was never seen, and the blind sector,
// turned to it, opens none of it.
TEST(ParticleMaps, ABlindBeamGivesNoFreeSpaceInAnyParticlesMap) {
  auto opens_west = [](bool masked) {
    ParticleMaps maps(options());
    const std::vector<ParticleState> first{{{3.0, 2.0, 0.0}, -1}, {{3.0, 2.0, 0.0}, -1}};
    EXPECT_TRUE(maps.update(first, scan_of(room_scan({3.0, 2.0, 0.0}, 6, 4)), scan_options()).ok);
    auto ranges = room_scan({3.0, 2.0, M_PI}, 6, 4);
    std::vector<std::uint8_t> blind(ranges.size(), 0);
    for (std::size_t i = 0; i < ranges.size(); ++i)
      if (std::abs(-M_PI / 2 + static_cast<double>(i) * M_PI / 180) < 0.5) {
        ranges[i] = 0.0f;
        blind[i] = masked ? 1 : 0;
      }
    SensorScan scan = scan_of(ranges);
    scan.blind = blind;
    const std::vector<ParticleState> second{{{3.0, 2.0, M_PI}, 0}, {{3.0, 2.0, M_PI}, 1}};
    const auto r = maps.update(second, scan, scan_options());
    EXPECT_TRUE(r.ok && r.scan_inserted) << r.error;
    int maps_open = 0;  // of the two, those free 2 m west of the robot
    for (std::size_t i = 0; i < 2; ++i) {
      const auto merged = maps.map(i).free_space();
      EXPECT_TRUE(merged.ok) << merged.error;
      for (const auto& p : merged.polygons)
        if (boost::geometry::within(pex::mapping::Point(1.0, 2.0), p.geometry)) {
          ++maps_open;
          break;
        }
    }
    return maps_open;
  };
  EXPECT_EQ(opens_west(true), 0);
  EXPECT_EQ(opens_west(false), 2) << "unmasked, the blind beams open 4 m into the unseen half";
}
