// The mapper's start from a saved map (initial_map_file).
#include "initial_map.hpp"

#include <cmath>
#include <limits>

#include <boost/geometry.hpp>
#include <gtest/gtest.h>

#include "test_maps.hpp"  // tools/map: the two-rooms map

namespace pex::polygon_mapper {
namespace {

TEST(InitialMap, PolygonsOfAMapAreItsRingsWithTheirEdgeTypes) {
  const auto map = map_files::two_rooms_map();
  const auto polygons = polygons_of(map);
  ASSERT_EQ(polygons.size(), 2u);
  EXPECT_EQ(polygons[0].geometry.inners().size(), 2u);
  ASSERT_EQ(polygons[0].edge_types.size(), 3u);
  EXPECT_EQ(polygons[0].edge_types[0].size(), 12u);
  EXPECT_EQ(polygons[0].edge_types[0][2], mapping::EdgeType::kFrontier);
  EXPECT_EQ(polygons[0].geometry.outer().size(), 13u);  // closed
  for (const auto& p : polygons) EXPECT_TRUE(boost::geometry::is_valid(p.geometry));
  auto bad = map;
  bad.rings[1].y[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(polygons_of(bad), std::invalid_argument);
}

MapperOptions options_for(const std::string& source) {
  MapperOptions o;
  o.pose_source = source;
  return o;
}

TEST(InitialMap, AMapperStartsFromTheSavedMapAndOnlyOnce) {
  Mapper mapper(options_for("sim_truth"));
  EXPECT_FALSE(mapper.map_message(1).has_value());
  ASSERT_EQ(mapper.start_from(polygons_of(map_files::two_rooms_map())), "");
  const auto msg = mapper.map_message(2);
  ASSERT_TRUE(msg.has_value());
  // The two-rooms floor and the island (83.2 m^2), less what the planning map's
  // obstacle band takes along the walls; its frontiers stay frontiers.
  EXPECT_GT(msg->free_area_m2, 60.0);
  EXPECT_LT(msg->free_area_m2, 83.3);
  EXPECT_GT(msg->frontier_length_m, 5.0);
  EXPECT_NE(mapper.start_from(polygons_of(map_files::two_rooms_map())), "");  // held already
}

TEST(InitialMap, ASlamMapperTakesTheSavedMapUpAtTheFirstUpdateWhateverItsEpoch) {
  Mapper mapper(options_for("slam"));
  ASSERT_EQ(mapper.start_from(polygons_of(map_files::two_rooms_map())), "");
  const double saved_m2 = mapper.map_message(1)->free_area_m2;
  // One scan (a half disc of 2 m ahead of the robot at (2, 2)) and its update.
  pex::laser_scan_t scan{};
  scan.utime = 1'000'000;
  scan.angle_min = static_cast<float>(-M_PI / 2);
  scan.angle_increment = static_cast<float>(M_PI / 180);
  scan.range_min = 0.05f;
  scan.range_max = 20.0f;
  scan.ranges.assign(181, 2.0f);
  scan.nranges = 181;
  mapper.on_scan(scan);
  pex::slam_update_t u{};
  u.utime = scan.utime + 1000;
  u.scan_utime = scan.utime;
  u.epoch = 42;  // a SLAM that knows nothing of the saved map
  u.best = 0;
  pex::particle_t p{};
  p.x = 2.0;
  p.y = 2.0;
  p.parent = -1;
  u.particles = {p, p};
  u.nparticles = 2;
  mapper.on_slam_update(u);
  EXPECT_EQ(mapper.counters().slam_updates, 1);
  EXPECT_EQ(mapper.counters().slam_epoch_changes, 0);
  const auto msg = mapper.map_message(2'000'000);
  ASSERT_TRUE(msg.has_value());
  EXPECT_EQ(msg->particle, 0);
  // The saved map with the scan in it (whose walls' band takes a little of it).
  EXPECT_GT(msg->free_area_m2, saved_m2 - 2.0);
  EXPECT_GT(saved_m2, 60.0);
}

}  // namespace
}  // namespace pex::polygon_mapper
