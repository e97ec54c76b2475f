#include "sim/sim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

namespace pex::sim {
namespace {

World parse_ok(const std::string& text) {
  auto result = parse_world(text, "test.wkt");
  if (auto* e = std::get_if<WorldError>(&result)) ADD_FAILURE() << e->message;
  return std::get<World>(result);
}

std::string parse_error(const std::string& text) {
  auto result = parse_world(text, "test.wkt");
  if (auto* e = std::get_if<WorldError>(&result)) return e->message;
  return "";
}

// A 10 x 6 m box with a pillar.
const char* kBox =
    "# a box\n"
    "START 2 3 0\n"
    "LINESTRING(0 0, 10 0, 10 6, 0 6, 0 0)\n"
    "POLYGON((6 2.5, 7 2.5, 7 3.5, 6 3.5, 6 2.5))\n";

TEST(World, ParsesGeometriesAndStart) {
  World w = parse_ok(kBox);
  EXPECT_EQ(w.walls.size(), 8u);
  EXPECT_DOUBLE_EQ(w.start.x_m, 2.0);
  EXPECT_DOUBLE_EQ(w.start.y_m, 3.0);
  EXPECT_DOUBLE_EQ(w.max_x, 10.0);
  EXPECT_DOUBLE_EQ(w.max_y, 6.0);
  // Multi-line geometry, MULTI*, a polygon with a hole, zero-length edge dropped.
  World m = parse_ok(
      "MULTILINESTRING((0 0, 1 0, 1 0), (5 5, 6 6))\n"
      "POLYGON((0 0, 4 0, 4 4, 0 4, 0 0),\n"
      "        (1 1, 1 2, 2 2, 2 1, 1 1))\n"
      "MULTIPOLYGON(((10 10, 11 10, 11 11, 10 10)))\n");
  EXPECT_EQ(m.walls.size(), 2u + 4u + 4u + 3u);
}

TEST(World, ErrorsNameTheLine) {
  EXPECT_NE(parse_error("# nothing\n").find("no walls"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 1 1)\nPOINT(1 2)\n").find("test.wkt:2: unsupported"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 1 1)\n\nLINESTRING(0 0, x 1)\n").find("test.wkt:3: bad WKT"),
            std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 1 1\n").find("not closed"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 1 1))\n").find("unbalanced"), std::string::npos);
  EXPECT_NE(parse_error("START 1 2\nLINESTRING(0 0, 1 1)\n").find("test.wkt:1: START"), std::string::npos);
  EXPECT_NE(parse_error("START 1 2 nan\nLINESTRING(0 0, 1 1)\n").find("START"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 1e9 1)\n").find("beyond"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, inf 1)\n"), "");
  // A solid whose ring is not closed: an edge would be missing.
  EXPECT_NE(parse_error("LINESTRING(0 0, 9 0)\nPOLYGON((1 1, 2 1, 2 2))\n").find("test.wkt:2: POLYGON ring not closed"),
            std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 9 0)\nPOLYGON((1 1, 2 1, 2 2, 1 1), (1.2 1.1, 1.8 1.1, 1.8 1.5))\n")
                .find("hole not closed"),
            std::string::npos);
}

TEST(World, StartMustBeOnTheFloor) {
  const char* room = "LINESTRING(0 0, 10 0, 10 8, 0 8, 0 0)\nPOLYGON((4 4, 5 4, 5 5, 4 5, 4 4))\n";
  EXPECT_NE(parse_error(std::string("START 4.5 4.5 0\n") + room).find("test.wkt:1: START (4.5"), std::string::npos);
  EXPECT_NE(parse_error(std::string("START 4.5 4.5 0\n") + room).find("inside a solid obstacle"), std::string::npos);
  EXPECT_NE(parse_error(std::string("START 12 3 0\n") + room).find("outside the world"), std::string::npos);
  EXPECT_NE(parse_error(std::string("START 3 -1 0\n") + room).find("outside the world"), std::string::npos);
  // In a solid's hole is floor (a courtyard).
  parse_ok("START 5 5 0\nPOLYGON((0 0, 10 0, 10 10, 0 10, 0 0), (3 3, 7 3, 7 7, 3 7, 3 3))\n");
  // On the floor, but closer to a wall than the robot's radius: the simulator refuses it.
  const World near_wall = parse_ok(std::string("START 4.5 3.9 0\n") + room);
  const RayCaster walls(near_wall);
  EXPECT_NE(check_start_clearance(near_wall, walls, 0.25).find("0.1"), std::string::npos);
  EXPECT_EQ(check_start_clearance(near_wall, walls, 0.05), "");
}

TEST(RayCaster, HitsTheRightWallAtTheRightDistance) {
  World w = parse_ok(kBox);
  RayCaster caster(w);
  EXPECT_EQ(caster.wall_count(), 8u);
  // From (2, 3): east hits the pillar's west face at x = 6, west the wall at x = 0.
  EXPECT_NEAR(caster.cast(2, 3, 0.0, 20.0), 4.0, 1e-12);
  EXPECT_NEAR(caster.cast(2, 3, std::numbers::pi, 20.0), 2.0, 1e-12);
  EXPECT_NEAR(caster.cast(2, 3, std::numbers::pi / 2, 20.0), 3.0, 1e-12);
  // 45 deg down-left from (2, 3): hits y = 0 at (-1, 0)? no: x = 0 first at (0, 1): 2 sqrt 2.
  EXPECT_NEAR(caster.cast(2, 3, -3.0 * std::numbers::pi / 4, 20.0), 2.0 * std::sqrt(2.0), 1e-12);
  // Above the pillar (y = 5), east: the outer wall at x = 10.
  EXPECT_NEAR(caster.cast(2, 5, 0.0, 20.0), 8.0, 1e-12);
  // Out of range: max range.
  EXPECT_DOUBLE_EQ(caster.cast(2, 5, 0.0, 5.0), 5.0);
  // Outside the box looking away: nothing.
  EXPECT_DOUBLE_EQ(caster.cast(-5, 3, std::numbers::pi, 20.0), 20.0);
}

// A glass pane across the box at x = 5 (y 0 .. 6), an opaque wall behind it
// at x = 10: the body runs into the pane; the laser sees it head-on and looks
// through it at a slant.
const char* kGlassBox =
    "START 2 3 0\n"
    "LINESTRING(0 0, 10 0, 10 6, 0 6, 0 0)\n"
    "GLASS LINESTRING(5 0,\n"
    "                 5 6)\n";

TEST(World, GlassIsMarkedOnItsGeometryOnly) {
  World w = parse_ok(kGlassBox);
  ASSERT_EQ(w.walls.size(), 5u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_FALSE(w.walls[i].glass) << i;
  EXPECT_TRUE(w.walls[4].glass);
  World m = parse_ok("glass MULTIPOLYGON(((1 1, 2 1, 2 2, 1 1)))\nLINESTRING(0 0, 9 0)\n");
  ASSERT_EQ(m.walls.size(), 4u);
  EXPECT_TRUE(m.walls[0].glass && m.walls[1].glass && m.walls[2].glass);
  EXPECT_FALSE(m.walls[3].glass);
  EXPECT_NE(parse_error("LINESTRING(0 0, 9 0)\nGLASS\n").find("test.wkt:2: GLASS needs a geometry"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 9 0)\nGLASS(1 1, 2 2)\n").find("test.wkt:2: GLASS needs"), std::string::npos);
  EXPECT_NE(parse_error("LINESTRING(0 0, 9 0)\nGLASS POINT(1 1)\n").find("test.wkt:2: unsupported"), std::string::npos);
  // A glass box is solid: START may not be inside it.
  EXPECT_NE(parse_error("START 1.5 1.5 0\nLINESTRING(0 0, 9 0)\nGLASS POLYGON((1 1, 2 1, 2 2, 1 2, 1 1))\n")
                .find("inside a solid"),
            std::string::npos);
}

TEST(RayCaster, ABeamPassesGlassAtASlantTheBodyNever) {
  World w = parse_ok(kGlassBox);
  RayCaster caster(w);
  const double deg = std::numbers::pi / 180.0;
  // Head-on (0 deg from the pane's normal) and 8 deg off: the pane, 3 m away.
  EXPECT_NEAR(caster.cast_beam(2, 3, 0.0, 20.0, 10 * deg), 3.0, 1e-12);
  EXPECT_NEAR(caster.cast_beam(2, 3, 8 * deg, 20.0, 10 * deg), 3.0 / std::cos(8 * deg), 1e-9);
  // 12 deg off: through the pane to the far wall at x = 10.
  EXPECT_NEAR(caster.cast_beam(2, 3, 12 * deg, 20.0, 10 * deg), 8.0 / std::cos(12 * deg), 1e-9);
  EXPECT_NEAR(caster.cast_beam(2, 3, -30 * deg, 20.0, 10 * deg), 3.0 / std::sin(30 * deg), 1e-9);  // the floor's wall y = 0 beyond the pane
  // 90 deg: glass is any wall; 0 deg: seen by no beam but one exactly along its normal.
  EXPECT_NEAR(caster.cast_beam(2, 3, 12 * deg, 20.0, 90 * deg), 3.0 / std::cos(12 * deg), 1e-9);
  EXPECT_NEAR(caster.cast_beam(2, 3.5, 1 * deg, 20.0, 0.0), 8.0 / std::cos(1 * deg), 1e-9);
  // The body's cast and the clearance count the pane at every angle.
  EXPECT_NEAR(caster.cast(2, 3, 40 * deg, 20.0), 3.0 / std::cos(40 * deg), 1e-9);
  EXPECT_NEAR(caster.clearance(4.5, 3, 2.0), 0.5, 1e-12);

  // The simulated laser: head-on beams return from the pane, slanted ones from the far wall.
  LaserOptions o;
  o.range_noise_sigma_m = 0.0;
  Laser laser(o, 1);
  const std::vector<float> ranges = laser.scan(caster, w.start);
  const int ahead = o.beam_count() / 2;  // the beam along the robot's x axis
  EXPECT_NEAR(ranges[static_cast<std::size_t>(ahead)], 3.0, 1e-5);
  EXPECT_NEAR(ranges[static_cast<std::size_t>(ahead + 40)], 8.0 / std::cos(20 * deg), 1e-4);  // 20 deg left
  o.glass_max_incidence_deg = 91.0;
  EXPECT_NE(o.validate(), "");

  // The robot drives into the pane, not through it.
  DiffDrivePlant::Options po;
  DiffDrivePlant plant(po, Pose2{2, 3, 30 * deg}, 1);
  for (int i = 0; i < 1000; ++i) plant.step(0.01, 10.0, 10.0, &caster);
  // (At a slant the refusal along the heading lets the disk's edge touch:
  // a contact, as against any wall.)
  EXPECT_LT(plant.pose().x_m, 5.0 - 0.2);
  EXPECT_GT(plant.pose().x_m, 4.0);
  EXPECT_EQ(plant.contacts(), 1u);
}

TEST(Laser, Lms111DefaultsNoiseAndDeterminism) {
  LaserOptions o;
  EXPECT_EQ(o.beam_count(), 541);
  EXPECT_EQ(o.validate(), "");
  World w = parse_ok(kBox);
  RayCaster caster(w);
  Laser a(o, 99), b(o, 99), c(o, 100);
  auto ra = a.scan(caster, w.start);
  auto rb = b.scan(caster, w.start);
  auto rc = c.scan(caster, w.start);
  ASSERT_EQ(ra.size(), 541u);
  EXPECT_EQ(ra, rb);   // same seed, same scan, bit for bit
  EXPECT_NE(ra, rc);
  // Beam 270 looks straight ahead: 4 m to the pillar, noise ~12 mm.
  EXPECT_NEAR(ra[270], 4.0, 0.06);
  // The noise statistics over many scans of the same beam.
  double sum = 0, sum2 = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double e = a.scan(caster, w.start)[270] - 4.0;
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.002);
  EXPECT_NEAR(sigma, 0.012, 0.001);
  // A world with no wall behind: beams there read max range exactly. (A short
  // wall far off gives the world an extent the start is in.)
  World open = parse_ok("LINESTRING(5 -100, 5 100)\nLINESTRING(-50 -100, -49 -100)\n");
  RayCaster open_caster(open);
  auto r = a.scan(open_caster, Pose2{0, 0, 0});
  EXPECT_FLOAT_EQ(r.front(), 20.0f);  // -135 deg: nothing
  EXPECT_NEAR(r[270], 5.0, 0.06);
}

TEST(Plant, StraightTurnBiasAndSlip) {
  DiffDrivePlant::Options o;
  DiffDrivePlant exact(o, Pose2{}, 1);
  // 1 m at 0.5 m/s: wheel rate 5 rad/s, 200 steps of 10 ms.
  for (int i = 0; i < 200; ++i) exact.step(0.01, 5.0, 5.0);
  EXPECT_NEAR(exact.pose().x_m, 1.0, 1e-9);
  EXPECT_NEAR(exact.pose().y_m, 0.0, 1e-12);
  // Turn in place by pi/2: wheels +-, arc of each = base/2 * pi/2.
  DiffDrivePlant turn(o, Pose2{}, 1);
  const double wheel_rad = 0.25 * std::numbers::pi / 2 / 0.1;
  for (int i = 0; i < 100; ++i) turn.step(0.01, -wheel_rad, wheel_rad);
  EXPECT_NEAR(turn.pose().theta_rad, std::numbers::pi / 2, 1e-9);
  EXPECT_NEAR(turn.pose().x_m, 0.0, 1e-12);
  // A larger right wheel curves the path to the left.
  o.right_radius_bias = 0.01;
  DiffDrivePlant biased(o, Pose2{}, 1);
  for (int i = 0; i < 200; ++i) biased.step(0.01, 5.0, 5.0);
  EXPECT_GT(biased.pose().y_m, 0.0);
  EXPECT_GT(biased.pose().theta_rad, 0.0);
  // Slip: the same seed gives the same path, another seed another one.
  o.right_radius_bias = 0.0;
  o.slip_sigma = 0.02;
  DiffDrivePlant s1(o, Pose2{}, 5), s2(o, Pose2{}, 5), s3(o, Pose2{}, 6);
  for (int i = 0; i < 200; ++i) {
    s1.step(0.01, 5.0, 5.0);
    s2.step(0.01, 5.0, 5.0);
    s3.step(0.01, 5.0, 5.0);
  }
  EXPECT_EQ(s1.pose().x_m, s2.pose().x_m);
  EXPECT_EQ(s1.pose().theta_rad, s2.pose().theta_rad);
  EXPECT_NE(s1.pose().x_m, s3.pose().x_m);
  EXPECT_NEAR(s1.pose().x_m, 1.0, 0.02);
}

TEST(Plant, StopsAtWalls) {
  World w = parse_ok(kBox);
  RayCaster caster(w);
  DiffDrivePlant::Options o;
  DiffDrivePlant plant(o, w.start, 1);
  for (int i = 0; i < 1000; ++i) plant.step(0.01, 10.0, 10.0, &caster);  // 1 m/s for 10 s towards the pillar at x = 6
  EXPECT_LT(plant.pose().x_m, 6.0 - o.robot_radius_m + 1e-9);
  EXPECT_GT(plant.pose().x_m, 5.0);
  EXPECT_GT(plant.refused_steps(), 1u);
  EXPECT_EQ(plant.contacts(), 1u);  // pressing on the pillar for seconds is one contact
}

TEST(RayCaster, ClearanceIsTheDistanceToTheNearestWall) {
  World w = parse_ok(kBox);
  RayCaster caster(w);
  EXPECT_NEAR(caster.clearance(2.0, 3.0, 10.0), 2.0, 1e-12);   // the left wall at x = 0
  EXPECT_NEAR(caster.clearance(5.0, 3.0, 10.0), 1.0, 1e-12);   // the pillar's face at x = 6
  EXPECT_NEAR(caster.clearance(7.5, 4.0, 10.0), std::hypot(0.5, 0.5), 1e-12);  // the pillar's corner (7, 3.5)
  EXPECT_EQ(caster.clearance(5.0, 3.0, 0.5), 0.5);               // nothing within 0.5 m
}

// Contacts begun: a disk that drives into the pillar, backs off clear of it and
// drives in again has two contacts; driving past a wall with a few cm to spare
// has none; sliding sideways into a wall (which the heading check misses) has one.
TEST(Plant, CountsContactsBegunNotStepsAgainstAWall) {
  World w = parse_ok(kBox);
  RayCaster caster(w);
  DiffDrivePlant::Options o;  // radius 0.25 m
  DiffDrivePlant plant(o, w.start, 1);
  auto drive = [&](double wheel_radps, int steps) {
    for (int i = 0; i < steps; ++i) plant.step(0.01, wheel_radps, wheel_radps, &caster);
  };
  drive(5.0, 800);  // 0.5 m/s towards the pillar at x = 6: stops at 5.75
  EXPECT_TRUE(plant.in_contact());
  EXPECT_EQ(plant.contacts(), 1u);
  drive(-5.0, 1);  // 5 mm back: still within the clearance, the same contact
  EXPECT_TRUE(plant.in_contact());
  drive(5.0, 50);
  EXPECT_EQ(plant.contacts(), 1u);
  drive(-5.0, 100);  // 0.5 m back: clear
  EXPECT_FALSE(plant.in_contact());
  drive(5.0, 200);
  EXPECT_EQ(plant.contacts(), 2u);

  // Along the bottom wall (y = 0) 5 cm clear of it: no contact.
  DiffDrivePlant along(o, Pose2{1.0, o.robot_radius_m + 0.05, 0.0}, 1);
  for (int i = 0; i < 300; ++i) along.step(0.01, 5.0, 5.0, &caster);
  EXPECT_GT(along.pose().x_m, 2.0);
  EXPECT_EQ(along.contacts(), 0u);
  EXPECT_EQ(along.refused_steps(), 0u);

  // Heading 0.2 rad towards the bottom wall from 0.5 mm off it: the heading
  // check lets the disk close in until its ray sees the wall; the clearance
  // counts the touch whatever the refusal did.
  DiffDrivePlant sliding(o, Pose2{1.0, o.robot_radius_m + 0.0005, -0.2}, 1);
  sliding.step(0.01, 5.0, 5.0, &caster);
  EXPECT_EQ(sliding.contacts(), 1u);
}

TEST(World, ShippedWorldsLoadAndHaveTheirSize) {
  struct Expect {
    const char* name;
    double min_w, min_h;
  };
  for (auto [name, min_w, min_h] : {Expect{"office", 38, 18}, Expect{"lab", 28, 28}, Expect{"loop", 60, 40},
                                    Expect{"campus", 150, 150}, Expect{"two_rooms", 11, 6}, Expect{"intel", 28, 28}}) {
    const std::string path = std::string(PEX_SOURCE_DIR) + "/worlds/" + name + ".wkt";
    std::ifstream in(path);
    ASSERT_TRUE(in) << path;
    std::stringstream text;
    text << in.rdbuf();
    World w = parse_ok(text.str());
    EXPECT_GE(w.max_x - w.min_x, min_w) << name;
    EXPECT_GE(w.max_y - w.min_y, min_h) << name;
    // The start pose is in free space: no wall within the robot radius.
    RayCaster caster(w);
    for (int k = 0; k < 36; ++k) {
      EXPECT_GT(caster.cast(w.start.x_m, w.start.y_m, k * std::numbers::pi / 18, 20.0), 0.4) << name;
    }
  }
}

}  // namespace
}  // namespace pex::sim
