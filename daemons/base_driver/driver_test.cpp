// base_driver: its config (the shipped file is read completely; bad values are
// refused) and its core against two simulated CiA 402 drives on an in-memory
// bus, time passed in: no process, no socket, no sleep.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <linux/can/error.h>
#include <pex/daemon_status_t.hpp>

#include "driver.hpp"
#include "driver_core.hpp"
#include "runtime/config.hpp"
#include "runtime/daemon.hpp"

namespace pex::base_driver {
namespace {

// The reason `fn` gives for refusing its input ("" when it takes it).
template <class Fn>
std::string refusal_of(Fn fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

using canopen::DriveNode;
using canopen::DriveState;
using canopen::Frame;
using canopen::NmtCommand;
using canopen::NmtState;

TEST(BaseDriverOptions, ShippedConfigLoadsCompletely) {
  auto config = runtime::ConfigReader::from_file(std::string(PEX_SOURCE_DIR) + "/config/base_driver.toml");
  runtime::load_runtime_options(config);  // read by run_daemon
  DriverOptions o = load_options(config);
  EXPECT_NO_THROW(config.finish());
  EXPECT_EQ(o.cmd_timeout_ms, 250);
  EXPECT_EQ(o.geometry.validate(), "");
  EXPECT_GE(o.odometry_rate_hz, 50.0);
}

TEST(BaseDriverOptions, BadValuesAreRefused) {
  for (const char* text : {"can_transport = \"usb\"\n", "left_node_id = 0\n", "left_node_id = 5\nright_node_id = 5\n",
                           "wheel_radius_m = -0.1\n", "cmd_timeout_ms = 0\n", "max_wheel_accel_mps2 = \"fast\"\n",
                           "counts_per_rev = 1e-300\n"}) {
    auto config = runtime::ConfigReader::from_string(text, "bad.toml");
    EXPECT_THROW(load_options(config), runtime::ConfigError) << text;
  }
}

// The stamping clock is another epoch than the monotonic one.
constexpr std::int64_t kUtimeOffset = 1'700'000'000'000'000;

struct Velocity {
  double v_mps;
  double omega_radps;
};

// A DriverCore and two simulated drives (the simulator's) on one bus, on the
// shipped defaults. Every 10 ms (control_rate_hz = 100): the drives step
// (heartbeats, EMCY), the core reads what they sent and runs a control step;
// its frames reach the drives at once and their answers (TPDO1, SDO) come
// back in the same period, as the shell's fd watch takes them. ODOMETRY every
// 20 ms (odometry_rate_hz = 50).
class Rig {
 public:
  explicit Rig(const DriverOptions& options = {}) : core(options, outputs()) {
    drives.emplace_back(DriveNode::Options{1, 100'000, 500'000.0});
    drives.emplace_back(DriveNode::Options{2, 100'000, 500'000.0});
  }

  // `ms` of time; with a velocity, a BASE_CMD of it before every control step.
  void run(int ms, std::optional<Velocity> command = {}) {
    for (int t = 0; t < ms; t += 10) {
      now_us += 10'000;
      if (command) {
        pex::velocity_cmd_t cmd{};
        cmd.v = command->v_mps;
        cmd.omega = command->omega_radps;
        cmd.source = "driver_test";
        EXPECT_NO_THROW(core.on_command(cmd, now_us));
      }
      for (auto& drive : drives)
        for (auto& f : drive.step(now_us)) to_core.push_back(f);
      deliver();
      step_sent.clear();
      core.control(now_us);
      deliver();
      if (++steps % 2 == 0) core.publish_odometry(now_us);
    }
  }
  // The drives alone, as after a kill -9 of the daemon.
  void run_without_core(int ms) {
    for (int t = 0; t < ms; t += 10) {
      now_us += 10'000;
      for (auto& drive : drives) drive.step(now_us);
    }
  }
  // A frame on the bus for the core (EMCY from a drive, an error frame).
  void inject(const Frame& frame) { to_core.push_back(frame); }

  // The RPDO1 to `node` in the last control step.
  std::optional<canopen::Rpdo1> rpdo(std::uint8_t node) const {
    for (const auto& f : step_sent)
      if (f.can_id == canopen::kCobRpdo1 + node) return canopen::read_rpdo1(f);
    return std::nullopt;
  }
  std::int32_t target(std::uint8_t node) const {
    auto r = rpdo(node);
    EXPECT_TRUE(r.has_value()) << "no RPDO1 to node " << int(node);
    return r ? r->target_velocity : -1;
  }
  bool sent_frame(const Frame& wanted) const {
    for (const auto& f : sent)
      if (f.can_id == wanted.can_id && f.can_dlc == wanted.can_dlc &&
          std::equal(f.data, f.data + f.can_dlc, wanted.data))
        return true;
    return false;
  }
  bool ok() const { return health.state == pex::daemon_status_t::STATE_OK; }
  double counts_per_m() const { return core.options().geometry.counts_per_m(); }

  std::int64_t now_us = 1'000'000;
  bool send_fails = false;
  std::vector<Frame> sent;       // every frame the core sent
  std::vector<Frame> step_sent;  // ... in the last control step
  std::vector<pex::odometry_t> odometry;
  runtime::DaemonHealth health;
  std::vector<std::pair<std::string, std::string>> errors, rejects;  // (key, text)
  DriverCore core;
  std::vector<DriveNode> drives;

 private:
  DriverOutputs outputs() {
    DriverOutputs out;
    out.send_frame = [this](const Frame& frame, std::string* error) {
      if (send_fails) {
        *error = "No buffer space available";
        return false;
      }
      sent.push_back(frame);
      step_sent.push_back(frame);
      for (auto& drive : drives)
        for (auto& answer : drive.handle(frame)) to_core.push_back(answer);
      return true;
    };
    out.publish_odometry = [this](const pex::odometry_t& msg) { odometry.push_back(msg); };
    out.report = [this](const runtime::DaemonHealth& h) { health = h; };
    out.error = [this](std::string_view key, const std::string& text) { errors.emplace_back(key, text); };
    out.reject = [this](std::string_view key, const std::string& text) { rejects.emplace_back(key, text); };
    return out;
  }
  void deliver() {
    std::vector<Frame> frames = std::exchange(to_core, {});
    core.on_frames(frames, now_us, now_us + kUtimeOffset);
  }

  std::vector<Frame> to_core;
  int steps = 0;
};

// What SocketCAN delivers on a bus error of that class.
Frame error_frame(std::uint32_t error_class) {
  Frame f{};
  f.can_id = CAN_ERR_FLAG | error_class;
  f.can_dlc = CAN_ERR_DLC;
  return f;
}

// Brought up, standing: where a test starts from.
void bring_up(Rig& rig) {
  rig.run(500);
  ASSERT_TRUE(rig.core.master().all_ready());
  ASSERT_TRUE(rig.ok());
}

TEST(DriverCore, BringsTheDrivesUpAndHoldsThemAtZeroWithoutACommand) {
  Rig rig;
  rig.run(10);
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_ERROR);
  EXPECT_EQ(rig.core.counters().stopped, 1);
  rig.run(500);
  EXPECT_TRUE(rig.core.master().all_ready());
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.health.reason, "no BASE_CMD: wheels held at zero");
  EXPECT_EQ(rig.target(1), 0);
  EXPECT_EQ(rig.target(2), 0);
  for (auto& drive : rig.drives) {
    EXPECT_EQ(drive.state(), DriveState::kOperationEnabled);
    EXPECT_EQ(drive.mode(), canopen::kModeProfileVelocity);
  }
}

TEST(DriverCore, CommandBecomesTheWheelVelocitiesOfTheRpdos) {
  Rig rig;
  bring_up(rig);
  rig.run(1000, Velocity{0.2, 0.4});  // the wheels ramp at 1 m/s^2 to 0.1 and 0.3 m/s
  const double half_base = 0.5 * rig.core.options().geometry.wheel_base_m;
  const double left = (0.2 - 0.4 * half_base) * rig.counts_per_m();
  const double right = (0.2 + 0.4 * half_base) * rig.counts_per_m();
  ASSERT_TRUE(rig.rpdo(1));
  EXPECT_EQ(rig.rpdo(1)->controlword, canopen::kCwEnableOperation);
  EXPECT_NEAR(rig.target(1), left, 1.0);
  EXPECT_NEAR(rig.target(2), right, 1.0);
  EXPECT_NEAR(rig.drives[0].velocity_actual(), left, 1.0);
  EXPECT_NEAR(rig.drives[1].velocity_actual(), right, 1.0);
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.health.reason, "");
  EXPECT_EQ(rig.core.counters().stopped, 0);
  EXPECT_EQ(rig.core.counters().commands, 100);
}

TEST(DriverCore, CommandsAreLimitedInSpeedAndAcceleration) {
  Rig rig;
  bring_up(rig);
  rig.run(10, Velocity{5.0, 0.0});  // 1 m/s^2 for 10 ms: 0.01 m/s
  EXPECT_NEAR(rig.target(1), 0.01 * rig.counts_per_m(), 1.0);
  rig.run(2000, Velocity{5.0, 0.0});  // max_speed_mps = 1
  EXPECT_NEAR(rig.target(1), 1.0 * rig.counts_per_m(), 1.0);
  EXPECT_NEAR(rig.target(2), 1.0 * rig.counts_per_m(), 1.0);
}

TEST(DriverCore, StaleCommandBringsTheWheelsToZeroAfterTheTimeout) {
  Rig rig;
  bring_up(rig);
  rig.run(1000, Velocity{0.3, 0.0});
  const double full = 0.3 * rig.counts_per_m();
  rig.run(250);  // 250 ms without a command: not yet stale (cmd_timeout_ms = 250)
  EXPECT_NEAR(rig.target(1), full, 1.0);
  EXPECT_EQ(rig.health.reason, "");
  EXPECT_EQ(rig.core.counters().cmd_timeouts, 0);
  rig.run(10);  // stale: down the ramp, not a jump
  EXPECT_LT(rig.target(1), full - 1.0);
  EXPECT_GT(rig.target(1), 0);
  EXPECT_EQ(rig.core.counters().cmd_timeouts, 1);
  rig.run(400);
  EXPECT_EQ(rig.target(1), 0);
  EXPECT_EQ(rig.target(2), 0);
  EXPECT_EQ(rig.drives[0].velocity_actual(), 0.0);
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.health.reason, "no BASE_CMD: wheels held at zero");
  EXPECT_EQ(rig.core.counters().stopped, 1);
  EXPECT_EQ(rig.core.counters().cmd_timeouts, 1);  // once per loss of commands
  rig.run(100, Velocity{0.3, 0.0});
  EXPECT_GT(rig.target(1), 0);
}

TEST(DriverCore, CommandsOverTheLimitsAreClippedAndCountedAbsurdOnesRefused) {
  Rig rig;
  bring_up(rig);
  rig.run(1000, Velocity{0.2, 0.0});
  const DriverOptions& o = rig.core.options();
  pex::velocity_cmd_t cmd{};
  cmd.source = "test";
  cmd.v = 1.5 * o.limits.max_speed_mps;  // "as fast as allowed": taken, clipped
  EXPECT_NO_THROW(rig.core.on_command(cmd, rig.now_us));
  EXPECT_EQ(rig.core.counters().commands_clipped, 1);
  cmd.v = 1e9;  // no sane sender's
  const std::string why = refusal_of([&] { rig.core.on_command(cmd, rig.now_us); });
  EXPECT_NE(why.find("more than 10 x the limits"), std::string::npos) << why;
  cmd.v = 0.0;
  cmd.omega = -1e9;
  EXPECT_THROW(rig.core.on_command(cmd, rig.now_us), std::invalid_argument);
  EXPECT_EQ(rig.core.counters().commands_clipped, 1);
  // Commanded over the limit (a command every 10 ms for 2 s): each counted,
  // the wheels at the limit, never more.
  rig.run(2000, Velocity{1.5 * o.limits.max_speed_mps, 0.0});
  EXPECT_EQ(rig.core.counters().commands_clipped, 1 + 200);
  EXPECT_LE(rig.target(1), o.limits.max_speed_mps * rig.counts_per_m() + 1.0);
  EXPECT_GT(rig.target(1), 0.9 * o.limits.max_speed_mps * rig.counts_per_m());
}

TEST(DriverCore, NonFiniteCommandIsRefusedAndTheCommandInForceKept) {
  Rig rig;
  bring_up(rig);
  rig.run(1000, Velocity{0.2, 0.0});
  pex::velocity_cmd_t bad{};
  bad.v = std::nan("");
  bad.source = "fuzzer";
  EXPECT_EQ(refusal_of([&] { rig.core.on_command(bad, rig.now_us); }),
            "BASE_CMD with a non-finite velocity from 'fuzzer'");
  bad.v = 0.0;
  bad.omega = INFINITY;
  EXPECT_THROW(rig.core.on_command(bad, rig.now_us), std::invalid_argument);
  EXPECT_EQ(rig.core.counters().commands, 100);
  rig.run(10);
  EXPECT_NEAR(rig.target(1), 0.2 * rig.counts_per_m(), 1.0);
  // The refused ones did not refresh the command: it goes stale on time.
  rig.run(250);
  EXPECT_EQ(rig.core.counters().cmd_timeouts, 1);
}

TEST(DriverCore, DriveHeartbeatLostStopsBothWheelsAndSaysWhy) {
  Rig rig;
  bring_up(rig);
  rig.run(500, Velocity{0.2, 0.0});
  rig.drives[0].set_silent(true);
  rig.run(150, Velocity{0.2, 0.0});  // last heartbeat at most 250 ms ago: within heartbeat_timeout_ms
  EXPECT_TRUE(rig.ok());
  rig.run(250, Velocity{0.2, 0.0});
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_ERROR);
  EXPECT_EQ(rig.health.reason, "node 1: no heartbeat: wheels stopped");
  EXPECT_EQ(rig.target(2), 0);  // the other wheel too, at once
  EXPECT_EQ(rig.drives[1].velocity_actual(), 0.0);
  EXPECT_EQ(rig.core.counters().heartbeat_losses, 1);
  EXPECT_EQ(rig.core.counters().stopped, 1);
  rig.drives[0].set_silent(false);
  rig.run(1000, Velocity{0.2, 0.0});
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.health.reason, "");
  EXPECT_NEAR(rig.drives[0].velocity_actual(), 0.2 * rig.counts_per_m(), 1.0);
}

TEST(DriverCore, EmcyFaultStopsTheWheelsAndIsResetUntilTheDriveIsBack) {
  Rig rig;
  bring_up(rig);
  rig.run(500, Velocity{0.2, 0.0});
  rig.inject(rig.drives[1].inject_fault(0x2310));  // over-current
  rig.sent.clear();
  rig.run(20, Velocity{0.2, 0.0});  // the fault shows in the statusword of the next SYNC's TPDO1
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_ERROR);
  EXPECT_EQ(rig.health.reason, "node 2: fault (EMCY 0x2310): wheels stopped");
  EXPECT_EQ(rig.target(1), 0);
  EXPECT_EQ(rig.core.counters().node_faults, 1);
  EXPECT_EQ(rig.core.counters().emcy_frames, 1);
  rig.run(200, Velocity{0.2, 0.0});
  bool fault_reset = false;
  for (const auto& f : rig.sent)
    if (auto r = canopen::read_rpdo1(f); r && f.can_id == canopen::kCobRpdo1 + 2)
      fault_reset = fault_reset || (r->controlword & canopen::kCwFaultReset) != 0;
  EXPECT_TRUE(fault_reset) << "no fault reset edge sent to node 2";
  rig.run(1000, Velocity{0.2, 0.0});
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.drives[1].state(), DriveState::kOperationEnabled);
  EXPECT_NEAR(rig.drives[1].velocity_actual(), 0.2 * rig.counts_per_m(), 1.0);
  EXPECT_EQ(rig.core.counters().node_faults, 1);
}

TEST(DriverCore, NodeStoppedByNmtIsBroughtBackAndDrivesAgain) {
  Rig rig;
  bring_up(rig);
  rig.run(500, Velocity{0.2, 0.0});
  rig.drives[0].handle(canopen::nmt_frame(NmtCommand::kStop, 1));  // from someone else on the bus
  rig.sent.clear();
  rig.run(200, Velocity{0.2, 0.0});
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_ERROR);
  EXPECT_EQ(rig.health.reason.rfind("node 1: ", 0), 0u) << rig.health.reason;
  EXPECT_EQ(rig.target(2), 0);
  EXPECT_TRUE(rig.sent_frame(canopen::nmt_frame(NmtCommand::kEnterPreOperational, 1)));
  rig.run(1000, Velocity{0.2, 0.0});
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.drives[0].nmt_state(), NmtState::kOperational);
  EXPECT_NEAR(rig.drives[0].velocity_actual(), 0.2 * rig.counts_per_m(), 1.0);
}

TEST(DriverCore, CanErrorFrameStopsTheWheelsAtOnceAndHoldsThem) {
  Rig rig;
  bring_up(rig);
  rig.run(500, Velocity{0.2, 0.0});
  rig.inject(error_frame(CAN_ERR_BUSOFF));
  rig.run(10, Velocity{0.2, 0.0});
  EXPECT_EQ(rig.target(1), 0);
  EXPECT_EQ(rig.target(2), 0);
  EXPECT_EQ(rig.health.state, +pex::daemon_status_t::STATE_ERROR);
  EXPECT_EQ(rig.health.reason, "CAN error frame: wheels stopped");
  EXPECT_EQ(rig.core.counters().can_error_frames, 1);
  ASSERT_EQ(rig.errors.size(), 1u);
  EXPECT_EQ(rig.errors[0].first, "can");
  EXPECT_EQ(rig.errors[0].second, "CAN error frame, class 0x40");
  rig.run(480, Velocity{0.2, 0.0});  // error_frame_hold_ms = 500 since the frame came
  EXPECT_EQ(rig.target(1), 0);
  EXPECT_FALSE(rig.ok());
  rig.run(20, Velocity{0.2, 0.0});
  EXPECT_TRUE(rig.ok());
  EXPECT_GT(rig.target(1), 0);
  EXPECT_LT(rig.target(1), 0.05 * rig.counts_per_m());  // from standstill, up the ramp
}

// A stop shorter than the ramp down: the wheels start again from standstill,
// not from the speed the ramp had come down to.
TEST(DriverCore, AfterABusStopTheWheelsStartAgainFromStandstill) {
  DriverOptions options;
  options.error_frame_hold_ms = 50;
  Rig rig(options);
  bring_up(rig);
  rig.run(1000, Velocity{0.5, 0.0});
  rig.inject(error_frame(CAN_ERR_CRTL));
  rig.run(60, Velocity{0.5, 0.0});
  ASSERT_TRUE(rig.ok());
  EXPECT_GT(rig.target(1), 0);
  EXPECT_LE(rig.target(1), std::lround(0.01 * rig.counts_per_m()));  // one 10 ms step at 1 m/s^2
}

TEST(DriverCore, MalformedFrameIsCountedAndTheStateKept) {
  Rig rig;
  bring_up(rig);
  rig.run(300, Velocity{0.2, 0.0});
  rig.inject(canopen::make_frame(canopen::kCobTpdo1 + 1, {0x37, 0x02, 0x00}));  // TPDO1 of 3 bytes
  rig.run(10, Velocity{0.2, 0.0});
  EXPECT_EQ(rig.core.counters().can_frames_malformed, 1);
  EXPECT_TRUE(rig.ok());
  EXPECT_NEAR(rig.target(1), 0.2 * rig.counts_per_m(), 1.0);
}

TEST(DriverCore, FramesThatCannotBeSentAreCountedAsErrors) {
  Rig rig;
  bring_up(rig);
  rig.send_fails = true;
  rig.run(10);
  EXPECT_GE(rig.core.counters().can_send_errors, 3);  // SYNC and two RPDO1 at least
  ASSERT_FALSE(rig.errors.empty());
  EXPECT_EQ(rig.errors.back().first, "can_send");
  EXPECT_EQ(rig.errors.back().second, "No buffer space available");
}

TEST(DriverCore, ProducesItsHeartbeatEveryPeriodAndArmsTheDriveWatchdog) {
  Rig rig;
  bring_up(rig);
  rig.sent.clear();
  rig.run(1000, Velocity{0.2, 0.0});
  int heartbeats = 0;
  for (const auto& f : rig.sent)
    if (f.can_id == canopen::kCobHeartbeat + 127) {
      ++heartbeats;
      EXPECT_EQ(canopen::read_heartbeat(f), NmtState::kOperational);
    }
  EXPECT_EQ(heartbeats, 20);  // master_heartbeat_period_ms = 50
  for (auto& drive : rig.drives) {
    EXPECT_EQ(drive.consumer_heartbeat_time_us(), 150'000);
    EXPECT_EQ(drive.abort_option(), canopen::AbortConnectionOption::kQuickStop);
  }
  // The core is gone (kill -9): the drives stop the wheels on their own.
  rig.run_without_core(300);
  for (auto& drive : rig.drives) {
    EXPECT_EQ(drive.velocity_actual(), 0.0);
    EXPECT_EQ(drive.heartbeat_events(), 1u);
  }
}

TEST(DriverCore, OdometryIntegratesTheEncoderReadings) {
  Rig rig;
  bring_up(rig);
  rig.odometry.clear();
  rig.run(2000, Velocity{0.2, 0.0});
  ASSERT_EQ(rig.odometry.size(), 100u);  // odometry_rate_hz = 50
  const auto& straight = rig.odometry.back();
  const double travelled = rig.drives[0].position_actual() / rig.counts_per_m();
  EXPECT_GT(travelled, 0.3);
  EXPECT_NEAR(straight.x, travelled, 0.005);  // one period of the drive's motion
  EXPECT_NEAR(straight.y, 0.0, 1e-9);
  EXPECT_NEAR(straight.theta, 0.0, 1e-9);
  EXPECT_NEAR(straight.v, 0.2, 1e-3);
  EXPECT_GT(straight.covariance[0], 0.0);
  // Stamped on the stamping clock when the encoder pair came.
  EXPECT_EQ(straight.utime, rig.now_us + kUtimeOffset);
  // Turning on the spot: the heading follows the wheels' difference.
  rig.run(1500, Velocity{0.0, 0.5});
  const auto& turned = rig.odometry.back();
  const double b = rig.core.options().geometry.wheel_base_m;
  const double left = rig.drives[0].position_actual() / rig.counts_per_m();
  const double right = rig.drives[1].position_actual() / rig.counts_per_m();
  EXPECT_NEAR(turned.theta, (right - left) / b, 0.02);
  EXPECT_GT(turned.theta, 0.4);
  EXPECT_NEAR(turned.omega, 0.5, 1e-2);
}

TEST(DriverCore, OdometryIsWithheldWhenTheEncoderReadingsAreOld) {
  Rig rig;
  bring_up(rig);
  rig.run(200, Velocity{0.2, 0.0});
  for (auto& drive : rig.drives) drive.set_silent(true);
  rig.odometry.clear();
  rig.run(300, Velocity{0.2, 0.0});  // heartbeat_timeout_ms = 300 after the last reading
  const std::size_t published = rig.odometry.size();
  EXPECT_GT(published, 0u);
  rig.run(500, Velocity{0.2, 0.0});
  EXPECT_EQ(rig.odometry.size(), published);
  EXPECT_GE(rig.core.counters().odometry_withheld, 20);
}

TEST(DriverCore, NoOdometryBeforeTheFirstEncoderReading) {
  Rig rig;
  for (int i = 0; i < 10; ++i) rig.core.publish_odometry(1'000'000 + 20'000 * i);
  EXPECT_TRUE(rig.odometry.empty());
  EXPECT_EQ(rig.core.counters().odometry_withheld, 0);
}

TEST(DriverCore, DriveRestartRebaselinesTheOdometryWithoutAJump) {
  Rig rig;
  bring_up(rig);
  rig.run(1500, Velocity{0.2, 0.0});
  rig.drives[0].power_cycle();  // its encoder count restarts from zero
  rig.run(2000, Velocity{0.2, 0.0});
  EXPECT_EQ(rig.core.counters().node_restarts, 1);
  EXPECT_TRUE(rig.ok());
  EXPECT_EQ(rig.core.counters().odometry_jumps, 0);
  EXPECT_TRUE(rig.rejects.empty());
  for (std::size_t i = 1; i < rig.odometry.size(); ++i) {
    EXPECT_GE(rig.odometry[i].x, rig.odometry[i - 1].x - 1e-9) << i;
    EXPECT_NEAR(rig.odometry[i].theta, 0.0, 0.05) << i;
  }
}

TEST(DriverCore, ImplausibleEncoderJumpIsRejectedAndRebaselined) {
  Rig rig;
  bring_up(rig);
  rig.run(300, Velocity{0.2, 0.0});
  const double x = rig.odometry.back().x;
  // Node 1 reports a position 2 m away from one SYNC to the next.
  const auto& node = rig.core.master().nodes()[0];
  rig.inject(canopen::tpdo1_frame(1, node.statusword,
                                  node.position_actual + static_cast<std::int32_t>(2.0 * rig.counts_per_m())));
  rig.inject(canopen::tpdo1_frame(2, rig.core.master().nodes()[1].statusword,
                                  rig.core.master().nodes()[1].position_actual));
  rig.run(40, Velocity{0.2, 0.0});
  // The glitch and the return from it: each refused, each a new baseline.
  EXPECT_EQ(rig.core.counters().odometry_jumps, 2);
  ASSERT_EQ(rig.rejects.size(), 2u);
  EXPECT_EQ(rig.rejects[0].first, "encoder");
  EXPECT_EQ(rig.rejects[0].second, "implausible encoder jump: re-baselined");
  EXPECT_NEAR(rig.odometry.back().x, x, 0.05);
}

}  // namespace
}  // namespace pex::base_driver
