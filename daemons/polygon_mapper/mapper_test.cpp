#include "mapper.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "mapping/test_support.hpp"
#include "runtime/config.hpp"

namespace pex::polygon_mapper {
namespace {

TEST(PoseBuffer, InterpolatesAndWrapsTheta) {
  PoseBuffer buffer(10.0);
  ASSERT_TRUE(buffer.add({1'000'000, {0.0, 0.0, 3.0}}));
  ASSERT_TRUE(buffer.add({2'000'000, {2.0, 1.0, -3.0}}));  // turned 0.28 rad through pi
  mapping::Pose2 p;
  ASSERT_EQ(buffer.pose_at(1'500'000, 2'000'000, p), PoseBuffer::Lookup::kOk);
  EXPECT_NEAR(p.x, 1.0, 1e-12);
  EXPECT_NEAR(p.y, 0.5, 1e-12);
  EXPECT_NEAR(std::abs(p.theta), std::numbers::pi, 1e-9);
  EXPECT_EQ(buffer.pose_at(500'000, 2'000'000, p), PoseBuffer::Lookup::kTooOld);
  EXPECT_EQ(buffer.pose_at(2'500'000, 2'000'000, p), PoseBuffer::Lookup::kTooNew);
  EXPECT_EQ(buffer.pose_at(1'500'000, 100'000, p), PoseBuffer::Lookup::kGap);
  EXPECT_FALSE(buffer.add({3'000'000, {std::nan(""), 0.0, 0.0}}));
  EXPECT_FALSE(buffer.add({1'500'000, {0.0, 0.0, 0.0}}));  // out of order
}

pex::laser_scan_t make_scan(const std::vector<mapping::testing::Wall>& walls, const mapping::Pose2& pose,
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

TEST(MapperOptions, ShippedConfigLoadsAndSlamIsRefusedForNow) {
  auto config = runtime::ConfigReader::from_file(std::string(PEX_SOURCE_DIR) + "/config/polygon_mapper.toml");
  const auto options = load_options(config);
  config.get<int>("heartbeat_period_ms", 1000);  // read by run_daemon in the daemon
  EXPECT_NO_THROW(config.finish());
  EXPECT_EQ(options.pose_source, "odometry");
  auto slam = runtime::ConfigReader::from_string("pose_source = \"slam\"\n", "test");
  EXPECT_THROW(load_options(slam), runtime::ConfigError);
}

}  // namespace
}  // namespace pex::polygon_mapper
