#include "evaluation/carmen_log.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <sstream>

namespace pex::evaluation {
namespace {

TEST(CarmenLog, ParsesFlaserOdomAndRobotlaser) {
  std::istringstream text(
      "# comment\n"
      "PARAM robot_frontlaser_offset 0.0 nohost 0\n"
      "ODOM 1.0 2.0 0.5 0.3 0.1 0.0 100.25 host 100.3\n"
      "FLASER 3 1.0 2.0 81.83 0.1 0.2 0.3 1.1 1.2 1.3 101.5 host 101.6\n"
      "ROBOTLASER1 0 -1.5 3.0 1.5 50.0 0.01 0 3 4.0 5.0 50.0 0 0.5 0.6 0.7 1.5 1.6 1.7 0 0 0 0 0 "
      "102.5 host 102.6\n");
  const CarmenLog log = parse_carmen_log(text);
  EXPECT_EQ(log.malformed_lines, 0u);
  ASSERT_EQ(log.odometry.size(), 1u);
  ASSERT_EQ(log.lasers.size(), 2u);
  ASSERT_EQ(log.order.size(), 3u);
  EXPECT_FALSE(log.order[0].is_laser);
  EXPECT_TRUE(log.order[1].is_laser);
  EXPECT_DOUBLE_EQ(log.odometry[0].timestamp_s, 100.25);
  EXPECT_DOUBLE_EQ(log.odometry[0].pose.theta_rad, 0.5);
  const CarmenLaser& flaser = log.lasers[0];
  EXPECT_DOUBLE_EQ(flaser.timestamp_s, 101.5);
  ASSERT_EQ(flaser.ranges_m.size(), 3u);
  EXPECT_FLOAT_EQ(flaser.ranges_m[2], 81.83f);
  EXPECT_DOUBLE_EQ(flaser.angle_min_rad, -std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(flaser.angle_increment_rad, std::numbers::pi / 2);  // odd count: both ends
  EXPECT_DOUBLE_EQ(flaser.odometry.x_m, 1.1);
  EXPECT_DOUBLE_EQ(flaser.laser_pose.theta_rad, 0.3);
  const CarmenLaser& robotlaser = log.lasers[1];
  EXPECT_DOUBLE_EQ(robotlaser.angle_min_rad, -1.5);
  EXPECT_DOUBLE_EQ(robotlaser.angle_increment_rad, 1.5);
  EXPECT_DOUBLE_EQ(robotlaser.max_range_m, 50.0);
  EXPECT_DOUBLE_EQ(robotlaser.odometry.theta_rad, 1.7);
  EXPECT_DOUBLE_EQ(robotlaser.timestamp_s, 102.5);
}

TEST(CarmenLog, EvenBeamCountStopsOneStepShortOfTheEnd) {
  CarmenMessage message;
  std::string error;
  ASSERT_EQ(parse_carmen_line("FLASER 180 " + std::string(180 * 2, ' ') , {}, message, error),
            LineKind::kMalformed);
  std::string line = "FLASER 180";
  for (int i = 0; i < 180; ++i) line += " 1.0";
  line += " 0 0 0 0 0 0 5.0 h 5.0";
  ASSERT_EQ(parse_carmen_line(line, {}, message, error), LineKind::kMessage);
  EXPECT_NEAR(std::get<CarmenLaser>(message).angle_increment_rad, std::numbers::pi / 180, 1e-12);
}

TEST(CarmenLog, MalformedLinesAreCountedAndSkipped) {
  std::istringstream text(
      "ODOM 1.0 2.0\n"
      "FLASER 99999999 1 2\n"
      "FLASER 2 1.0 nan 0 0 0 0 0 0 1.0 h 1.0\n"
      "FLASER -3 1.0\n"
      "ODOM 1.0 2.0 0.5 0.3 0.1 0.0 100.25 host 100.3\n");
  const CarmenLog log = parse_carmen_log(text);
  EXPECT_EQ(log.malformed_lines, 4u);
  EXPECT_FALSE(log.first_error.empty());
  EXPECT_EQ(log.odometry.size(), 1u);
  EXPECT_TRUE(log.lasers.empty());
}

}  // namespace
}  // namespace pex::evaluation
