#include "mapping/known_walls.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/test_support.hpp"

namespace pex::mapping {
namespace {

constexpr double kPi = std::numbers::pi;

// 181 beams over the half turn ahead (1 degree apart), all without a return.
std::vector<float> blind_scan() { return std::vector<float>(181, 0.0f); }
constexpr double kAngleMin = -kPi / 2, kStep = kPi / 180;

// A wall across x = 2 from y = -1 to y = 1 (26.6 degrees either side of
// straight ahead), blocking on the sensor's far side (walking a -> b
// northwards, the far side x > 2 is on the right).
KnownWall wall_ahead() { return {Point(2.0, -1.0), Point(2.0, 1.0)}; }
const double kWallEnd = std::atan(0.5);

TEST(NoReturnExtents, ABeamWithoutAReturnEndsAtTheFirstWallItRunsInto) {
  ScanPolygonOptions options;
  const std::vector<KnownWall> walls{{Point(3.0, -1.0), Point(3.0, 1.0)}, wall_ahead()};
  const auto ranges = blind_scan();
  const auto e = no_return_extents(ranges, kAngleMin, kStep, {0.0, 0.0, 0.0}, options, walls);
  ASSERT_EQ(e.extent_m.size(), ranges.size());
  // Straight ahead (beam 90): 2 m, the nearer wall; 20 degrees left:
  // 2 / cos 20; the wall ends at 26.6 degrees either side; beyond them
  // (and past the farther wall's ends, 18.4 degrees) the free range.
  EXPECT_NEAR(e.extent_m[90], 2.0, 1e-6);
  EXPECT_NEAR(e.extent_m[110], 2.0 / std::cos(20 * kPi / 180), 1e-6);
  EXPECT_NEAR(e.extent_m[64], 2.0 / std::cos(26 * kPi / 180), 1e-6);
  EXPECT_NEAR(e.extent_m[116], 2.0 / std::cos(26 * kPi / 180), 1e-6);
  EXPECT_EQ(e.extent_m[63], static_cast<float>(options.free_range_m));
  EXPECT_EQ(e.extent_m[117], static_cast<float>(options.free_range_m));
  EXPECT_LT(26 * kPi / 180, kWallEnd);
  EXPECT_EQ(e.beams_stopped, 53);  // -26 .. +26 degrees
}

TEST(NoReturnExtents, AWallIsNoStopForBeamsLeavingItsBlockedSide) {
  // The same wall turned round: its blocked side faces the sensor (the
  // sensor stands in the band of a wall, or behind a wall seen from the
  // other side): the beams leave it and go on.
  ScanPolygonOptions options;
  const KnownWall w = wall_ahead();
  const std::vector<KnownWall> walls{{w.b, w.a}};
  const auto e = no_return_extents(blind_scan(), kAngleMin, kStep, {0.0, 0.0, 0.0}, options, walls);
  EXPECT_EQ(e.beams_stopped, 0);
  EXPECT_TRUE(e.extent_m.empty());
}

TEST(NoReturnExtents, ReturnsAndWallsBeyondTheFreeRangeStopNothing) {
  ScanPolygonOptions options;
  options.free_range_m = 1.5;
  auto ranges = blind_scan();
  const std::vector<KnownWall> walls{wall_ahead()};
  EXPECT_EQ(no_return_extents(ranges, kAngleMin, kStep, {0.0, 0.0, 0.0}, options, walls).beams_stopped, 0);
  options.free_range_m = 4.0;
  for (auto& r : ranges) r = 1.0f;  // every beam returned, short of the wall
  EXPECT_EQ(no_return_extents(ranges, kAngleMin, kStep, {0.0, 0.0, 0.0}, options, walls).beams_stopped, 0);
}

TEST(NoReturnExtents, FollowsTheSensorsPoseAndAReversedScan) {
  ScanPolygonOptions options;
  const std::vector<KnownWall> walls{wall_ahead()};
  // The sensor at (1, 0) facing +y: the wall is on its right (beams -90 .. -45
  // degrees from its heading reach it, from 1 m to its end at sqrt 2).
  const geometry::Pose2 pose{1.0, 0.0, kPi / 2};
  const auto ranges = blind_scan();
  const auto e = no_return_extents(ranges, kAngleMin, kStep, pose, options, walls);
  EXPECT_NEAR(e.extent_m[0], 1.0, 1e-6);                           // -90 degrees: straight at it
  EXPECT_NEAR(e.extent_m[45], std::sqrt(2.0), 1e-6);               // -45: its upper end
  EXPECT_EQ(e.extent_m[46], static_cast<float>(options.free_range_m));
  // The same beams listed from +90 down to -90 degrees.
  const auto r = no_return_extents(ranges, -kAngleMin, -kStep, pose, options, walls);
  EXPECT_NEAR(r.extent_m[180], 1.0, 1e-6);
  EXPECT_NEAR(r.extent_m[135], std::sqrt(2.0), 1e-6);
  EXPECT_EQ(r.beams_stopped, e.beams_stopped);
}

TEST(NoReturnExtents, AWallAcrossTheFirstBeamsDirectionIsFound) {
  // A full turn of beams starting straight ahead: the wall ahead spans the
  // first beam's direction (angles -45 .. 45 degrees, that is 315 .. 45).
  ScanPolygonOptions options;
  const std::vector<float> ranges(360, std::numeric_limits<float>::quiet_NaN());
  const std::vector<KnownWall> walls{wall_ahead()};
  const auto e = no_return_extents(ranges, 0.0, kStep, {0.0, 0.0, 0.0}, options, walls);
  EXPECT_NEAR(e.extent_m[0], 2.0, 1e-6);
  EXPECT_NEAR(e.extent_m[10], 2.0 / std::cos(10 * kPi / 180), 1e-6);
  EXPECT_NEAR(e.extent_m[350], 2.0 / std::cos(10 * kPi / 180), 1e-6);
  EXPECT_EQ(e.extent_m[180], static_cast<float>(options.free_range_m));
  EXPECT_EQ(e.beams_stopped, 53);  // 0 .. 26 and 334 .. 359 degrees
}

TEST(ScanToPolygon, BeamsStoppedAtAWallEndThereAndTheRestReachTheFreeRange) {
  ScanPolygonOptions options;
  const auto ranges = blind_scan();
  const std::vector<KnownWall> walls{wall_ahead()};
  const auto e = no_return_extents(ranges, kAngleMin, kStep, {0.0, 0.0, 0.0}, options, walls);
  const auto open = scan_to_polygon(ranges, kAngleMin, kStep, {0.0, 0.0, 0.0}, options);
  const auto stopped = scan_to_polygon(ranges, kAngleMin, kStep, {0.0, 0.0, 0.0}, options, e.extent_m);
  ASSERT_TRUE(open.ok) << open.error;
  ASSERT_TRUE(stopped.ok) << stopped.error;
  // No vertex of the stopped polygon lies beyond the wall (beams past its
  // ends go on to the free range); the open one's go 2 m past it.
  int beyond = 0, at_wall = 0;
  for (const auto& p : stopped.polygon.geometry.outer()) {
    if (std::abs(p.y()) > 1.0) continue;
    beyond += p.x() > 2.0 + 1e-6 ? 1 : 0;
    at_wall += std::abs(p.x() - 2.0) < 1e-6 ? 1 : 0;
  }
  EXPECT_EQ(beyond, 0);
  EXPECT_EQ(at_wall, 53);
  // Half a disk of 4 m, less what lies behind the wall within it.
  EXPECT_NEAR(bg::area(open.polygon.geometry), 0.5 * kPi * 16.0, 0.1);
  EXPECT_LT(bg::area(stopped.polygon.geometry), bg::area(open.polygon.geometry) - 3.0);
  // Every edge of it is frontier: the scan saw no wall.
  for (const auto t : stopped.polygon.edge_types[0]) EXPECT_EQ(t, EdgeType::kFrontier);
  // Extents of the wrong length are bad input.
  const std::vector<float> short_extents(10, 1.0f);
  EXPECT_FALSE(scan_to_polygon(ranges, kAngleMin, kStep, {0.0, 0.0, 0.0}, options, short_extents).ok);
}

TEST(KnownWalls, AMapsObstacleBandStopsABlindSectorAndItsWallsStay) {
  // A 4 x 3 m room mapped from its middle, then a scan from the same place
  // with the 60 degrees ahead blind: the band of the wall ahead stops those
  // beams, so the room stays the room.
  std::vector<testing::Wall> room;
  testing::add_box(room, 0, 0, 4, 3);
  const testing::ScanSpec spec;
  const geometry::Pose2 at{2.0, 1.5, 0.0};
  ScanPolygonOptions options;
  PolygonMap map;
  const auto seen = testing::cast_scan(room, at, spec);
  const auto first = scan_to_polygon(seen, spec.angle_min, spec.angle_increment, at, options);
  ASSERT_TRUE(first.ok) << first.error;
  ASSERT_TRUE(map.insert(first.polygon).ok);
  const double room_m2 = map.free_area_m2();
  auto blind = seen;
  for (std::size_t i = 0; i < blind.size(); ++i) {
    const double a = spec.angle_min + spec.angle_increment * static_cast<double>(i);
    if (std::abs(a) < kPi / 6) blind[i] = 0.0f;
  }
  const auto walls = known_walls(map, {at.x_m, at.y_m}, options.free_range_m);
  ASSERT_FALSE(walls.empty());
  const auto e = no_return_extents(blind, spec.angle_min, spec.angle_increment, at, options, walls);
  EXPECT_GT(e.beams_stopped, 0);
  for (std::size_t i = 0; i < e.extent_m.size(); ++i) {
    if (blind[i] == 0.0f) {
      EXPECT_LE(e.extent_m[i], 2.0f / std::cos(kPi / 6) + 1e-3f) << "beam " << i;
    }
  }
  PolygonMap stopped = map, open = map;
  const auto with_stop = scan_to_polygon(blind, spec.angle_min, spec.angle_increment, at, options, e.extent_m);
  const auto without = scan_to_polygon(blind, spec.angle_min, spec.angle_increment, at, options);
  ASSERT_TRUE(with_stop.ok && without.ok);
  ASSERT_TRUE(stopped.insert(with_stop.polygon).ok);
  ASSERT_TRUE(open.insert(without.polygon).ok);
  EXPECT_NEAR(stopped.free_area_m2(), room_m2, 1e-3);
  EXPECT_GT(open.free_area_m2(), room_m2 + 1.0) << "the blind sector carves the wall away";
}

TEST(KnownWalls, APlanningMapsObstacleEdgesAreWallsItsFrontiersAreNot) {
  // A 4 x 2 m free rectangle: obstacle on the right (x = 4), frontier elsewhere.
  TypedPolygon free;
  free.geometry.outer() = {Point(0, 0), Point(4, 0), Point(4, 2), Point(0, 2), Point(0, 0)};
  free.edge_types = {{EdgeType::kFrontier, EdgeType::kObstacle, EdgeType::kFrontier, EdgeType::kFrontier}};
  const TypedMultiPolygon map{free};
  const auto walls = known_walls(map, {2.0, 1.0}, 4.0);
  ASSERT_EQ(walls.size(), 1u);
  ScanPolygonOptions options;
  const auto e = no_return_extents(blind_scan(), kAngleMin, kStep, {2.0, 1.0, 0.0}, options, walls);
  EXPECT_NEAR(e.extent_m[90], 2.0, 1e-6);
  EXPECT_EQ(known_walls(map, {-5.0, 1.0}, 4.0).size(), 0u);  // too far away
}

}  // namespace
}  // namespace pex::mapping
