#pragma once
// A map for the map files' tests (map_files_test, map_tool_test).
#include <cstdint>
#include <utility>
#include <vector>

#include <pex/polygon_map_t.hpp>

namespace pex::map_files {

inline constexpr std::int8_t kObstacle = pex::polygon_ring_t::EDGE_OBSTACLE;
inline constexpr std::int8_t kFrontier = pex::polygon_ring_t::EDGE_FRONTIER;

inline pex::polygon_ring_t ring(int polygon, bool hole, std::vector<std::pair<double, double>> points,
                         std::vector<std::int8_t> types) {
  pex::polygon_ring_t r{};
  r.polygon = polygon;
  r.hole = hole;
  for (const auto& [x, y] : points) {
    r.x.push_back(x);
    r.y.push_back(y);
  }
  r.nvertices = static_cast<std::int32_t>(points.size());
  r.edge_type = std::move(types);
  return r;
}

// The two_rooms world (worlds/two_rooms.wkt) as a mapped polygon: 12 x 7 m, a
// 10 cm dividing wall at x = 6 with the door at y in [4.5, 5.7], a pillar and
// a box as holes. The right room's top wall and the door are frontiers here,
// as in a map still being explored.
inline pex::polygon_map_t two_rooms_map() {
  pex::polygon_map_t m{};
  m.utime = 1'700'000'000'123'456;
  m.scan_utime = 1'700'000'000'100'000;
  m.particle = 3;
  m.generation = 42;
  m.scans_inserted = 17;
  m.robot_x = 2.0000000000000004;
  m.robot_y = 0.1 + 0.2;
  m.robot_theta = -3.141592653589793;
  m.free_area_m2 = 82.66;
  m.obstacle_length_m = 55.5;
  m.frontier_length_m = 7.15;
  m.rings.push_back(ring(0, false,
                         {{0, 0}, {5.95, 0}, {5.95, 4.5}, {6.05, 4.5}, {6.05, 0}, {12, 0}, {12, 7}, {6.05, 7},
                          {6.05, 5.7}, {5.95, 5.7}, {5.95, 7}, {0, 7}},
                         {kObstacle, kObstacle, kFrontier, kObstacle, kObstacle, kObstacle, kFrontier, kObstacle,
                          kFrontier, kObstacle, kObstacle, kObstacle}));
  m.rings.push_back(ring(0, true, {{8.5, 2}, {8.5, 2.8}, {9.3, 2.8}, {9.3, 2}}, {kObstacle, kObstacle, kObstacle, kObstacle}));
  m.rings.push_back(ring(0, true, {{2.5, 4.5}, {2.5, 5.2}, {3.5, 5.2}, {3.5, 4.5}}, {kObstacle, kObstacle, kObstacle, kObstacle}));
  // A second polygon: an island of free space seen through a window, odd doubles.
  m.rings.push_back(ring(1, false, {{20.1, 1.0 / 3.0}, {21.7, 1e-9}, {21.0, 2.2250738585072014e-308 + 2.0}},
                         {kFrontier, kObstacle, kFrontier}));
  m.nrings = static_cast<std::int32_t>(m.rings.size());
  m.vertex_count = 12 + 4 + 4 + 3;
  return m;
}


// The message's bytes: two maps are identical when these are.
inline std::vector<std::uint8_t> encoded(const pex::polygon_map_t& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

}  // namespace pex::map_files
