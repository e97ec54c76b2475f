// pex-sim as the clock source: a Simulator on an in-process LCM (memq://),
// with its sockets on loopback, run until it has published enough SIM_CLOCK
// messages. Asserts the clock's contract, not how fast the host ran it.
#include <unistd.h>

#include <chrono>
#include <optional>

#include <gtest/gtest.h>

#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>

#include "canopen/canopen.hpp"
#include "hwio/hwio.hpp"
#include "runtime/channels.hpp"
#include "runtime/node.hpp"
#include "runtime/run_guarded.hpp"
#include "simulator.hpp"

namespace pex::simd {
namespace {

namespace ch = runtime::channels;

// two_rooms at `speed`, the laser on any free loopback port, a CAN bus of its own.
SimOptions two_rooms_at(double speed, const std::string& bus_name) {
  SimOptions o;
  o.world_file = std::string(PEX_SOURCE_DIR) + "/worlds/two_rooms.wkt";
  o.speed_factor = speed;
  o.cola_port = 0;
  o.can_local_path = "@" + bus_name + "-" + std::to_string(getpid());
  return o;
}

TEST(SimClock, StepsInSimulatedTimeWithTruthOnTheSameTimeLineAndCountsContacts) {
  runtime::Node node(runtime::NodeOptions{"sim", "memq://", false, "", 1.0});
  SimOptions o = two_rooms_at(4.0, "pex-sim-clock-test");
  o.clock_rate_hz = 100.0;
  o.truth_rate_hz = 50.0;
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

// The drives' heartbeat watchdog (0x1016) fires when the master has gone
// silent, not because the master's next heartbeat is late in wall time while
// the simulated clock runs fast: the clock waits at the drive's deadline for
// pacing's silence time, then goes on, and the watchdog fires (EMCY 0x8130).
// At x20 without the wait, the 150 ms consumer time is 7.5 ms of wall time.
TEST(SimClock, WaitsAtADrivesWatchdogUntilItsMasterHasBeenSilentForTheSilenceTime) {
  runtime::Node node(runtime::NodeOptions{"sim", "memq://", false, "", 1.0});
  SimOptions o = two_rooms_at(20.0, "pex-sim-watchdog-test");
  o.pacing.silence_wall_s = 0.5;
  Simulator sim(node, o);
  auto master = hwio::connect_local_bus(o.can_local_path);
  ASSERT_TRUE(master) << master.error();
  hwio::FrameTransport& bus = **master;

  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  std::optional<Clock::time_point> heartbeat_sent, watchdog_fired;
  bool configured = false;
  std::string error;
  node.every(std::chrono::milliseconds(2), [&](std::int64_t) {
    while (auto frame = bus.receive()) {
      if (frame->can_id == canopen::kCobSdoTx + 1) configured = true;  // node 1 took the consumer time
      if (frame->can_id == canopen::kCobEmcy + 1 && heartbeat_sent && !watchdog_fired) {
        watchdog_fired = Clock::now();
        node.request_stop();
      }
    }
    if (!configured) {
      // Until the drive has booted and answers: consumer 0x7F, 150 ms (0x96).
      bus.send(canopen::sdo_write_frame(1, canopen::kObjConsumerHeartbeatTime, 1, 0x7F0096, 4), &error);
    } else if (!heartbeat_sent) {
      bus.send(canopen::heartbeat_frame(0x7F, canopen::NmtState::kOperational), &error);  // arms it; then silence
      heartbeat_sent = Clock::now();
    }
    if (Clock::now() - started > std::chrono::seconds(30)) node.request_stop();  // guard only
  });
  pex::runtime::run_guarded(node);

  ASSERT_TRUE(heartbeat_sent);
  ASSERT_TRUE(watchdog_fired) << "the watchdog never fired with the master silent";
  EXPECT_GE(std::chrono::duration<double>(*watchdog_fired - *heartbeat_sent).count(), o.pacing.silence_wall_s);
  EXPECT_GT(node.counter("watchdog_holds"), 0);
}

}  // namespace
}  // namespace pex::simd
