// The explorer explores a small simulated world on its own: pex-sim (world
// worlds/two_rooms.wkt), pex-lidar-reader, pex-base-driver, pex-polygon-mapper
// (poses from SIM_TRUTH, so no SLAM is involved) and pex-explorer (pose_channel
// SIM_TRUTH) on a real LCM bus in a private network namespace, every daemon on
// the simulator's clock (clock = "sim"). Each test waits for states
// (EXPLORE_STATE phases, SIM_CLOCK time), never for a fixed wall time.
//
//   - the mission at 10x speed ends DONE with the world mapped, no collision;
//   - the same mission at 1x and at 10x explores the same area (within a few
//     percent) without a collision: the speed changes only the wall time;
//   - with autostart off the robot waits for `pex-mission start`; pause stops
//     it, resume goes on, home brings it back to the start pose.
#include <gtest/gtest.h>

#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <regex>

#include "exploration_set.hpp"
#include "harness.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;

namespace {

// The world's free area, from the comment in worlds/two_rooms.wkt.
constexpr double kWorldFreeAreaM2 = 82.66;

struct Outcome {
  std::int8_t phase = -1;
  double explored_m2 = 0.0;
  double travelled_m = 0.0;
  std::int64_t collisions = -1;
};

// A whole mission on two_rooms at `speed`, to its end (at most 600 simulated s).
Outcome explore_two_rooms(double speed, const std::string& tag) {
  ExplorationSet m(tag, {.speed = speed});
  m.spin_to_end(600.0);
  m.bus().spin_for(500ms);  // the last commands after the end
  Outcome o;
  EXPECT_TRUE(m.state().has_value()) << m.report_with_logs();
  if (!m.state()) return o;
  o.phase = m.state()->phase;
  o.explored_m2 = m.state()->explored_area_m2;
  o.travelled_m = m.state()->distance_travelled_m;
  o.collisions = m.clock() ? m.clock()->collisions : -1;
  EXPECT_EQ(o.phase, +pex::explore_state_t::PHASE_DONE) << m.report_with_logs();
  // Most of the world is mapped (the map's free space loses a band along each
  // wall and the corners the laser never saw).
  EXPECT_GT(o.explored_m2, 0.8 * kWorldFreeAreaM2) << m.report();
  EXPECT_LT(o.explored_m2, 1.05 * kWorldFreeAreaM2) << m.report();
  // It had to drive: the right room is not visible from the start.
  EXPECT_GT(o.travelled_m, 3.0) << m.report();
  // Stopped at the end.
  EXPECT_TRUE(m.cmd() && m.cmd()->v == 0.0 && m.cmd()->omega == 0.0) << m.report();
  // The robot never touched a wall.
  EXPECT_EQ(o.collisions, 0) << m.report();
  auto explorer_status = m.bus().status().find("explorer");
  EXPECT_TRUE(explorer_status != m.bus().status().end() && explorer_status->second.msgs_rejected == 0)
      << m.report_with_logs();
  m.stop_all();
  std::cout << "speed x" << speed << ": " << m.report();
  m.clean_up(::testing::Test::HasFailure());
  return o;
}

}  // namespace

TEST(Exploration, ExploresTheTwoRoomsWorldAtTenTimesSpeed) {
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  const Outcome fast = explore_two_rooms(10.0, "explore-x10");
  EXPECT_EQ(fast.phase, +pex::explore_state_t::PHASE_DONE);
}

TEST(Exploration, SpeedChangesOnlyTheWallTimeNotTheOutcome) {
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  const Outcome slow = explore_two_rooms(1.0, "explore-x1");
  const Outcome fast = explore_two_rooms(10.0, "explore-x10b");
  ASSERT_EQ(slow.phase, +pex::explore_state_t::PHASE_DONE);
  ASSERT_EQ(fast.phase, +pex::explore_state_t::PHASE_DONE);
  // The same coverage within a few percent, and no collision in either run.
  EXPECT_NEAR(fast.explored_m2 / slow.explored_m2, 1.0, 0.04)
      << "x1: " << slow.explored_m2 << " m^2, x10: " << fast.explored_m2 << " m^2";
  EXPECT_EQ(slow.collisions, 0);
  EXPECT_EQ(fast.collisions, 0);
}

TEST(Exploration, MissionCommandsStartPauseResumeAndHome) {
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  ExplorationSet m("explore-commands", {.speed = 5.0, .autostart = false});

  // Booted without autostart: it waits, wheels still, for 10 simulated seconds.
  ASSERT_TRUE(m.spin_sim([&] { return m.phase() == pex::explore_state_t::PHASE_WAITING_START && m.truth(); }, 60.0))
      << m.report_with_logs();
  m.spin_sim([] { return false; }, 10.0);
  ASSERT_TRUE(m.first_truth() && m.truth());
  EXPECT_LT(std::hypot(m.truth()->x - m.first_truth()->x, m.truth()->y - m.first_truth()->y), 0.01) << m.report();
  EXPECT_EQ(m.phase(), +pex::explore_state_t::PHASE_WAITING_START);

  // start: it moves off.
  ASSERT_EQ(m.command("start"), 0) << m.report_with_logs();
  const pex::pose_t start = *m.first_truth();
  ASSERT_TRUE(m.spin_sim(
      [&] { return m.truth() && std::hypot(m.truth()->x - start.x, m.truth()->y - start.y) > 1.0; }, 120.0))
      << m.report_with_logs();

  // pause: the wheels stop and stay stopped while paused.
  ASSERT_EQ(m.command("pause"), 0) << m.report_with_logs();
  m.spin_sim([] { return false; }, 2.0);  // let the base come to rest
  const pex::pose_t paused_at = *m.truth();
  m.spin_sim([] { return false; }, 10.0);
  EXPECT_EQ(m.phase(), +pex::explore_state_t::PHASE_PAUSED);
  EXPECT_LT(std::hypot(m.truth()->x - paused_at.x, m.truth()->y - paused_at.y), 0.02) << m.report();
  ASSERT_TRUE(m.cmd());
  EXPECT_EQ(m.cmd()->v, 0.0);
  EXPECT_EQ(m.cmd()->omega, 0.0);

  // resume: it moves again.
  ASSERT_EQ(m.command("resume"), 0) << m.report_with_logs();
  EXPECT_TRUE(m.spin_sim(
      [&] { return std::hypot(m.truth()->x - paused_at.x, m.truth()->y - paused_at.y) > 0.5 || mission_finished(m.phase()); },
      120.0))
      << m.report_with_logs();

  // home: back to the start pose, then stopped there.
  ASSERT_EQ(m.command("home"), 0) << m.report_with_logs();
  ASSERT_TRUE(m.spin_sim([&] { return m.phase() == pex::explore_state_t::PHASE_HOME; }, 300.0))
      << m.report_with_logs();
  EXPECT_LT(std::hypot(m.truth()->x - start.x, m.truth()->y - start.y), 0.5) << m.report();
  // Stopped there: the wheels are commanded to zero, and once the base has
  // come to rest (it was driving when HOME came: a few cm of braking) it
  // stays, as after the pause.
  ASSERT_TRUE(m.cmd());
  EXPECT_EQ(m.cmd()->v, 0.0);
  EXPECT_EQ(m.cmd()->omega, 0.0);
  m.spin_sim([] { return false; }, 2.0);
  const pex::pose_t home_at = *m.truth();
  m.spin_sim([] { return false; }, 5.0);
  EXPECT_EQ(m.phase(), +pex::explore_state_t::PHASE_HOME);
  EXPECT_LT(std::hypot(m.truth()->x - home_at.x, m.truth()->y - home_at.y), 0.02) << m.report();
  EXPECT_EQ(m.clock()->collisions, 0) << m.report();
  m.stop_all();
  std::cout << m.report();
  m.clean_up(HasFailure());
}
