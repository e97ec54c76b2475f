// pex-sim as the clock source: a Simulator on an in-process LCM (memq://),
// with its sockets on loopback, run until it has published enough SIM_CLOCK
// messages. Asserts the clock's contract, not how fast the host ran it.
#include <unistd.h>

#include <gtest/gtest.h>

#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>

#include "runtime/channels.hpp"
#include "runtime/node.hpp"
#include "runtime/run_guarded.hpp"
#include "simulator.hpp"

namespace pex::simd {
namespace {

namespace ch = runtime::channels;

TEST(SimClock, StepsInSimulatedTimeWithTruthOnTheSameTimeLineAndCountsContacts) {
  runtime::Node node(runtime::NodeOptions{"sim", "memq://", false, "", 1.0});
  SimOptions o;
  o.world_file = std::string(PEX_SOURCE_DIR) + "/worlds/two_rooms.wkt";
  o.speed_factor = 4.0;
  o.clock_rate_hz = 100.0;
  o.truth_rate_hz = 50.0;
  o.cola_port = 0;  // any free port
  o.can_local_path = "@pex-sim-clock-test-" + std::to_string(getpid());
  // Parked against a wall (the outer wall at x = 0): one contact, no motion.
  o.start_override = true;
  o.start = geometry::Pose2{o.plant.robot_radius_m - 0.01, 3.5, 0.0};

  std::vector<pex::sim_clock_t> clocks;
  std::vector<pex::pose_t> truths;
  node.subscribe<pex::sim_clock_t>(ch::kSimClock, [&](const pex::sim_clock_t& c) {
    clocks.push_back(c);
    if (clocks.size() >= 60) node.request_stop();
  });
  node.subscribe<pex::pose_t>(ch::kSimTruth, [&](const pex::pose_t& p) { truths.push_back(p); });
  Simulator sim(node, o);
  pex::runtime::run_guarded(node);  // until the state above is reached

  ASSERT_GE(clocks.size(), 60u);
  const std::int64_t epoch = clocks[0].utime - clocks[0].sim_time_us;
  EXPECT_EQ(clocks[0].sim_time_us, 10'000);
  for (std::size_t i = 0; i < clocks.size(); ++i) {
    const auto& c = clocks[i];
    EXPECT_EQ(c.utime - c.sim_time_us, epoch) << i;  // utime = wall time at start + simulated time
    EXPECT_EQ(c.speed_factor, 4.0);
    if (i > 0) {
      EXPECT_EQ(c.sim_time_us - clocks[i - 1].sim_time_us, 10'000) << i;  // 100 Hz of simulated time
    }
    EXPECT_EQ(c.collisions, 1) << i;
    EXPECT_EQ(c.collision_steps, 0) << i;  // nothing moved into the wall
  }
  // SIM_TRUTH is on the clock's time line: at 50 Hz, every truth stamp is a
  // tick of the 100 Hz clock.
  ASSERT_GE(truths.size(), 10u);
  for (const auto& t : truths) {
    EXPECT_EQ((t.utime - epoch) % 10'000, 0) << t.utime - epoch;
    EXPECT_LE(t.utime, clocks.back().utime + 20'000);
  }
  // The same counts go to DAEMON_STATUS.
  EXPECT_EQ(node.counter("collisions"), 1);
  EXPECT_EQ(node.counter("collision_steps"), 0);
}

}  // namespace
}  // namespace pex::simd
