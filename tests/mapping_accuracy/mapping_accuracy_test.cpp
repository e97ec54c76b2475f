// Drive a known trajectory through worlds/two_rooms.wkt with a noise-free
// LMS111 (pex_sim's ray caster) and compare the polygon map with the world:
// IoU of the free-space map with the world's free space >= 0.97, and >= 99 %
// of the obstacle-typed edge length within a few centimetres of a real wall
// (evaluation::obstacle_on_wall, exact lengths).
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include <gtest/gtest.h>

#include "evaluation/obstacle_on_wall.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/scan_polygon.hpp"
#include "sim/sim.hpp"

namespace pex::mapping {
namespace {

using geometry::Pose2;

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Poses every 0.1 m along the waypoints, heading along the motion, turning in
// place (0.2 rad steps) at each waypoint.
std::vector<Pose2> trajectory(const std::vector<std::pair<double, double>>& waypoints) {
  std::vector<Pose2> poses;
  double heading = 0.0;
  for (std::size_t k = 0; k + 1 < waypoints.size(); ++k) {
    const auto [x0, y0] = waypoints[k];
    const auto [x1, y1] = waypoints[k + 1];
    const double target = std::atan2(y1 - y0, x1 - x0);
    double turn = geometry::wrap_angle(target - heading);
    while (std::abs(turn) > 0.2) {
      heading += std::copysign(0.2, turn);
      poses.push_back({x0, y0, heading});
      turn = geometry::wrap_angle(target - heading);
    }
    heading = target;
    const double length = std::hypot(x1 - x0, y1 - y0);
    for (double s = 0.0; s < length; s += 0.1)
      poses.push_back({x0 + s / length * (x1 - x0), y0 + s / length * (y1 - y0), heading});
  }
  return poses;
}

TEST(MappingAccuracy, TwoRoomsNoiseFree) {
  const std::string path = std::string(PEX_SOURCE_DIR) + "/worlds/two_rooms.wkt";
  auto parsed = sim::parse_world(read_file(path), path);
  ASSERT_TRUE(std::holds_alternative<sim::World>(parsed)) << std::get<sim::WorldError>(parsed).message;
  const auto& world = std::get<sim::World>(parsed);
  const sim::RayCaster caster(world);
  sim::LaserOptions laser_options;
  laser_options.range_noise_sigma_m = 0.0;
  sim::Laser laser(laser_options, 1);

  // The world's free space: the 12 x 7 m hall minus the pillar and the box
  // (the dividing wall is a line: no area). Same as the file's comment.
  MultiPolygon world_free;
  {
    Polygon hall, pillar, box;
    bg::read_wkt("POLYGON((0 0,12 0,12 7,0 7,0 0))", hall);
    bg::read_wkt("POLYGON((8.5 2,9.3 2,9.3 2.8,8.5 2.8,8.5 2))", pillar);
    bg::read_wkt("POLYGON((2.5 4.5,3.5 4.5,3.5 5.2,2.5 5.2,2.5 4.5))", box);
    bg::correct(hall), bg::correct(pillar), bg::correct(box);
    MultiPolygon tmp;
    bg::difference(hall, pillar, tmp);
    bg::difference(tmp, box, world_free);
  }
  ASSERT_NEAR(bg::area(world_free), 82.66, 1e-6);

  // Left room around the box, through the door, right room around the pillar.
  const auto poses = trajectory({{2.0, 2.0}, {4.5, 1.5}, {4.8, 3.8}, {1.5, 3.8}, {1.5, 6.2}, {4.8, 6.2},
                                 {5.0, 5.1}, {7.2, 5.1}, {10.8, 5.8}, {10.8, 1.2}, {7.2, 1.2},
                                 {7.2, 3.6}, {10.8, 3.6}});
  ScanPolygonOptions scan_options;
  scan_options.range_min_m = laser_options.min_range_m;
  scan_options.range_max_m = laser_options.max_range_m;
  PolygonMap map;
  int inserted = 0, refused = 0;
  for (const auto& pose : poses) {
    const auto ranges = laser.scan(caster, pose);
    const auto scan = scan_to_polygon(ranges, laser_options.first_angle_rad(), laser_options.step_deg * std::numbers::pi / 180.0,
                                      pose, scan_options);
    ASSERT_TRUE(scan.ok) << scan.error;
    const auto r = map.insert(scan.polygon);
    if (!r.ok) ++refused;  // survived: the map keeps its last good state
    ++inserted;
  }
  EXPECT_GT(inserted, 200);
  // A scan is refused when Boost's overlay fails on it (degenerate contacts
  // with tile corners); that must stay rare.
  EXPECT_LE(refused, inserted / 50);

  const auto free_space = map.free_space();
  ASSERT_TRUE(free_space.ok) << free_space.error;
  const MultiPolygon mapped = geometry_of(free_space.polygons);
  MultiPolygon inter, uni;
  bg::intersection(mapped, world_free, inter);
  bg::union_(mapped, world_free, uni);
  const double iou = bg::area(inter) / bg::area(uni);
  const double on_walls = evaluation::obstacle_on_wall(free_space.polygons, world, 0.03);
  RecordProperty("iou", std::to_string(iou));
  RecordProperty("obstacle_share_on_walls", std::to_string(on_walls));
  std::printf("free map: IoU %.4f, obstacle length on walls %.4f, %zu vertices\n", iou, on_walls,
              vertex_count(free_space.polygons));
  EXPECT_GE(iou, 0.97);
  EXPECT_GE(on_walls, 0.99);

  // The planning map (free minus the obstacle band): its obstacle edges lie
  // obstacle_inner_m from a wall seen from one side, obstacle_outer_m from a
  // thin wall seen from both sides (the dividing wall: each side's band
  // reaches beyond it into the other room).
  const auto planning = map.planning_map();
  ASSERT_TRUE(planning.ok) << planning.error;
  const double planning_on_walls =
      evaluation::obstacle_on_wall(planning.polygons, world, map.options().obstacle_outer_m + 0.03);
  std::printf("planning map: obstacle length on walls %.4f, %zu vertices, %.2f m2\n", planning_on_walls,
              vertex_count(planning.polygons), area(planning.polygons));
  EXPECT_GE(planning_on_walls, 0.99);
}

}  // namespace
}  // namespace pex::mapping
