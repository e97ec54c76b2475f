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

// Issue 12: poses of 1e308 and timestamps of -1e18 s went through to
// pex-carmen2lcm. Each line below is the good line of its kind with one
// number made absurd; the good lines themselves are taken.
TEST(CarmenLog, AbsurdNumbersMakeTheLineMalformed) {
  const std::string odom = "ODOM 1.0 2.0 0.5 0.3 0.1 0.0 100.25 host 100.3\n";
  const std::string flaser = "FLASER 3 1.0 2.0 81.83 0.1 0.2 0.3 1.1 1.2 1.3 101.5 host 101.6\n";
  const std::string robotlaser =
      "ROBOTLASER1 0 -1.5 3.0 1.5 50.0 0.01 0 3 4.0 5.0 50.0 0 0.5 0.6 0.7 1.5 1.6 1.7 0 0 0 0 0 102.5 host 102.6\n";
  std::istringstream good(odom + flaser + robotlaser);
  const CarmenLog taken = parse_carmen_log(good);
  EXPECT_EQ(taken.malformed_lines, 0u) << taken.first_error;
  EXPECT_EQ(taken.order.size(), 3u);

  auto with = [](std::string line, const std::string& from, const std::string& to) {
    const auto at = line.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return line.replace(at, from.size(), to);
  };
  for (const std::string& line : {
           with(odom, "1.0 2.0", "1e308 2.0"),            // x
           with(odom, "100.25", "-1e18"),                 // timestamp
           with(odom, "100.25", "1e300"),                 // timestamp (overflows int64 us)
           with(odom, "0.3 0.1", "1e9 0.1"),              // tv
           with(flaser, "0.1 0.2 0.3", "0.1 1e308 0.3"),  // laser pose y
           with(flaser, "1.1 1.2 1.3", "1.1 1.2 -1e300"), // odometry theta
           with(flaser, "2.0 81.83", "2.0 1e300"),        // a range (beyond a float)
           with(flaser, "1.0 2.0 81.83", "-1.0 2.0 81.83"),  // a negative range
           with(flaser, "101.5", "-5"),                   // timestamp
           with(robotlaser, "-1.5 3.0 1.5 50.0", "-1.5 3.0 0 50.0"),     // resolution 0
           with(robotlaser, "-1.5 3.0 1.5 50.0", "-1.5 3.0 1.5 1e300"),  // maximum range
           with(robotlaser, "-1.5 3.0", "-1e9 3.0"),      // start angle
           with(robotlaser, "0.5 0.6 0.7", "0.5 1e200 0.7"),  // laser pose
           with(robotlaser, "102.5", "-1e18"),            // timestamp
       }) {
    std::istringstream text(line);
    const CarmenLog log = parse_carmen_log(text);
    EXPECT_EQ(log.malformed_lines, 1u) << line;
    EXPECT_TRUE(log.order.empty()) << line;
  }
}

}  // namespace
}  // namespace pex::evaluation
