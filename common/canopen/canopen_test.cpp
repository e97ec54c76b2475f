#include "canopen/canopen.hpp"

#include <gtest/gtest.h>

#include <linux/can/error.h>

namespace pex::canopen {
namespace {

TEST(CanopenFrames, LayoutIsLittleEndianWithTheDocumentedIds) {
  Frame r = rpdo1_frame(2, kCwEnableOperation, -1000);
  EXPECT_EQ(r.can_id, 0x202u);
  EXPECT_EQ(r.can_dlc, 6);
  EXPECT_EQ(r.data[0], 0x0F);
  EXPECT_EQ(r.data[1], 0x00);
  EXPECT_EQ(r.data[2], 0x18);  // -1000 = 0xFFFFFC18
  EXPECT_EQ(r.data[3], 0xFC);
  EXPECT_EQ(r.data[5], 0xFF);
  auto back = read_rpdo1(r);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->target_velocity, -1000);
  Frame t = tpdo1_frame(1, 0x0627, 0x12345678);
  EXPECT_EQ(t.can_id, 0x181u);
  EXPECT_EQ(read_tpdo1(t)->position_actual, 0x12345678);
  Frame s = sdo_write_frame(1, kObjModesOfOperation, 0, 3, 1);
  EXPECT_EQ(s.can_id, 0x601u);
  EXPECT_EQ(s.data[0], 0x2F);
  EXPECT_EQ(s.data[1], 0x60);
  EXPECT_EQ(s.data[2], 0x60);
  EXPECT_EQ(s.data[4], 3);
  Frame n = nmt_frame(NmtCommand::kStart, 5);
  EXPECT_EQ(n.can_id, 0u);
  EXPECT_EQ(n.data[0], 1);
  EXPECT_EQ(n.data[1], 5);
  EXPECT_EQ(heartbeat_frame(3, NmtState::kPreOperational).can_id, 0x703u);
}

TEST(CanopenFrames, MalformedFramesAreRejected) {
  Frame short_pdo = tpdo1_frame(1, 0x27, 5);
  short_pdo.can_dlc = 5;
  EXPECT_FALSE(read_tpdo1(short_pdo));
  Frame rtr = tpdo1_frame(1, 0x27, 5);
  rtr.can_id |= CAN_RTR_FLAG;
  EXPECT_FALSE(read_tpdo1(rtr));
  Frame ext = heartbeat_frame(1, NmtState::kOperational);
  ext.can_id |= CAN_EFF_FLAG;
  EXPECT_FALSE(read_heartbeat(ext));
  Frame bad_state = make_frame(0x701, {0x33});
  EXPECT_FALSE(read_heartbeat(bad_state));
  Frame bad_dlc = make_frame(0x701, {0x05, 0x00});
  EXPECT_FALSE(read_heartbeat(bad_dlc));
  Frame wrong_function = rpdo1_frame(1, 0, 0);
  EXPECT_FALSE(read_tpdo1(wrong_function));
  Frame huge_dlc = tpdo1_frame(1, 0, 0);
  huge_dlc.can_dlc = 15;
  EXPECT_FALSE(read_tpdo1(huge_dlc));
}

TEST(CanopenStatusword, DecodesEveryState) {
  EXPECT_EQ(decode_statusword(0x0000), DriveState::kNotReadyToSwitchOn);
  EXPECT_EQ(decode_statusword(0x0250), DriveState::kSwitchOnDisabled);
  EXPECT_EQ(decode_statusword(0x0231), DriveState::kReadyToSwitchOn);
  EXPECT_EQ(decode_statusword(0x0233), DriveState::kSwitchedOn);
  EXPECT_EQ(decode_statusword(0x0237), DriveState::kOperationEnabled);
  EXPECT_EQ(decode_statusword(0x0217), DriveState::kQuickStopActive);
  EXPECT_EQ(decode_statusword(0x021F), DriveState::kFaultReactionActive);
  EXPECT_EQ(decode_statusword(0x0218), DriveState::kFault);
}

// A bus with a master and two drive nodes: frames sent in one step are
// delivered before the next, time advances 10 ms per step.
class Bus {
 public:
  Bus() : master_(Cia402Master::Options{}) {
    nodes_.emplace_back(DriveNode::Options{1, 100'000, 200'000.0});
    nodes_.emplace_back(DriveNode::Options{2, 100'000, 200'000.0});
  }
  void run(int steps, std::vector<std::int32_t> target) {
    for (int s = 0; s < steps; ++s) {
      now_us_ += 10'000;
      std::vector<Frame> to_master;
      for (auto& node : nodes_) {
        for (auto& f : node.step(now_us_)) to_master.push_back(f);
      }
      for (auto& f : master_.step(now_us_, target)) {
        ++frames_from_master_;
        for (auto& node : nodes_) {
          for (auto& answer : node.handle(f)) to_master.push_back(answer);
        }
      }
      for (auto& f : to_master) master_.handle(f, now_us_);
    }
  }
  // The master is gone (kill -9): the drives run on their own; what they send
  // goes nowhere. Returns the EMCY codes they sent.
  std::vector<std::uint16_t> run_without_master(int steps) {
    std::vector<std::uint16_t> emcy;
    for (int s = 0; s < steps; ++s) {
      now_us_ += 10'000;
      for (auto& node : nodes_)
        for (auto& f : node.step(now_us_))
          if ((f.can_id & 0x780) == kCobEmcy && f.can_dlc == 8) emcy.push_back(static_cast<std::uint16_t>(f.data[0] | (f.data[1] << 8)));
    }
    return emcy;
  }
  Cia402Master master_;
  std::vector<DriveNode> nodes_;
  std::int64_t now_us_ = 1'000'000;
  int frames_from_master_ = 0;
};

TEST(Cia402, MasterBringsNodesToOperationEnabledAndDrives) {
  Bus bus;
  EXPECT_FALSE(bus.master_.all_ready());
  bus.run(30, {1000, -2000});
  ASSERT_TRUE(bus.master_.all_ready());
  for (auto& node : bus.nodes_) {
    EXPECT_EQ(node.state(), DriveState::kOperationEnabled);
    EXPECT_EQ(node.nmt_state(), NmtState::kOperational);
    EXPECT_EQ(node.mode(), kModeProfileVelocity);
  }
  bus.run(100, {1000, -2000});  // 1 s at speed
  EXPECT_DOUBLE_EQ(bus.nodes_[0].velocity_actual(), 1000.0);
  EXPECT_DOUBLE_EQ(bus.nodes_[1].velocity_actual(), -2000.0);
  // The master sees the positions the nodes report (one step of lag at most).
  EXPECT_NEAR(bus.master_.nodes()[0].position_actual, bus.nodes_[0].position_actual(), 11.0);
  EXPECT_NEAR(bus.master_.nodes()[1].position_actual, bus.nodes_[1].position_actual(), 21.0);
  EXPECT_GT(bus.master_.nodes()[0].position_actual, 900);
}

TEST(Cia402, FaultIsResetAndTheNodeComesBack) {
  Bus bus;
  bus.run(30, {500, 500});
  ASSERT_TRUE(bus.master_.all_ready());
  Frame emcy = bus.nodes_[1].inject_fault(0x2310);  // over-current
  bus.master_.handle(emcy, bus.now_us_);
  bus.run(1, {500, 500});
  EXPECT_FALSE(bus.master_.all_ready());
  EXPECT_EQ(bus.master_.nodes()[1].drive_state, DriveState::kFault);
  EXPECT_EQ(bus.master_.nodes()[1].faults, 1u);
  EXPECT_EQ(bus.master_.nodes()[1].last_emcy_code, 0x2310);
  bus.run(60, {500, 500});
  EXPECT_TRUE(bus.master_.all_ready());
  EXPECT_EQ(bus.nodes_[1].state(), DriveState::kOperationEnabled);
}

TEST(Cia402, MissedHeartbeatIsDetectedAndRecovered) {
  Bus bus;
  bus.run(30, {0, 0});
  ASSERT_TRUE(bus.master_.all_ready());
  bus.nodes_[0].set_silent(true);
  bus.run(15, {0, 0});  // last heartbeat at most 100 + 150 ms ago: within the 300 ms timeout
  EXPECT_FALSE(bus.master_.nodes()[0].heartbeat_lost);
  bus.run(20, {0, 0});
  EXPECT_TRUE(bus.master_.nodes()[0].heartbeat_lost);
  EXPECT_EQ(bus.master_.nodes()[0].heartbeat_losses, 1u);
  EXPECT_FALSE(bus.master_.all_ready());
  bus.nodes_[0].set_silent(false);
  bus.run(40, {0, 0});
  EXPECT_FALSE(bus.master_.nodes()[0].heartbeat_lost);
  EXPECT_TRUE(bus.master_.all_ready());
}

TEST(Cia402, PowerCycledNodeIsReconfigured) {
  Bus bus;
  bus.run(30, {100, 100});
  ASSERT_TRUE(bus.master_.all_ready());
  bus.nodes_[0].power_cycle();
  bus.run(1, {100, 100});
  EXPECT_EQ(bus.master_.nodes()[0].restarts, 1u);
  EXPECT_FALSE(bus.master_.all_ready());
  // Its position from before the restart is no reading of the new counter:
  // none until the drive sends one again (the odometry re-baselines on it).
  EXPECT_FALSE(bus.master_.nodes()[0].position_seen);
  EXPECT_TRUE(bus.master_.nodes()[1].position_seen);
  bus.run(40, {100, 100});
  EXPECT_TRUE(bus.master_.all_ready());
  EXPECT_EQ(bus.nodes_[0].mode(), kModeProfileVelocity);
}

TEST(Cia402, NodeIgnoresMalformedAndForeignFrames) {
  DriveNode node(DriveNode::Options{});
  node.step(0);  // boot-up
  EXPECT_TRUE(node.handle(sdo_write_frame(1, kObjModesOfOperation, 0, 3, 1)).size() == 1);
  EXPECT_TRUE(node.handle(nmt_frame(NmtCommand::kStart, 1)).empty());
  Frame short_rpdo = rpdo1_frame(1, kCwShutdown, 0);
  short_rpdo.can_dlc = 2;
  node.handle(short_rpdo);
  EXPECT_EQ(node.state(), DriveState::kSwitchOnDisabled);
  node.handle(rpdo1_frame(2, kCwShutdown, 0));  // other node
  EXPECT_EQ(node.state(), DriveState::kSwitchOnDisabled);
  node.handle(rpdo1_frame(1, kCwShutdown, 0));
  EXPECT_EQ(node.state(), DriveState::kReadyToSwitchOn);
  // Unsupported mode and unknown object are aborted, not applied.
  auto abort = node.handle(sdo_write_frame(1, kObjModesOfOperation, 0, 1, 1));
  ASSERT_EQ(abort.size(), 1u);
  EXPECT_TRUE(read_sdo_response(abort[0])->abort);
  EXPECT_EQ(node.mode(), kModeProfileVelocity);
  abort = node.handle(sdo_write_frame(1, 0x1234, 0, 1, 1));
  EXPECT_EQ(read_sdo_response(abort[0])->abort_code, 0x06020000u);
}

TEST(Cia402, MasterCountsMalformedFramesAndKeepsState) {
  Bus bus;
  bus.run(30, {0, 0});
  ASSERT_TRUE(bus.master_.all_ready());
  Frame bad = tpdo1_frame(1, 0x0008, 0);  // would say Fault ...
  bad.can_dlc = 3;                         // ... but is too short
  bus.master_.handle(bad, bus.now_us_);
  Frame bad_hb = make_frame(0x702, {0x42});
  bus.master_.handle(bad_hb, bus.now_us_);
  Frame error_frame = make_frame(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0});
  bus.master_.handle(error_frame, bus.now_us_);
  EXPECT_EQ(bus.master_.counters().frames_malformed, 2u);
  EXPECT_TRUE(bus.master_.all_ready());
  EXPECT_EQ(bus.master_.nodes()[0].faults, 0u);
}

TEST(Cia402, QuickStopAndDisableTransitions) {
  DriveNode node(DriveNode::Options{});
  node.step(0);
  node.handle(sdo_write_frame(1, kObjModesOfOperation, 0, 3, 1));
  node.handle(nmt_frame(NmtCommand::kStart, 0));  // broadcast start
  EXPECT_EQ(node.nmt_state(), NmtState::kOperational);
  node.handle(rpdo1_frame(1, kCwSwitchOn, 0));  // not allowed from Switch On Disabled
  EXPECT_EQ(node.state(), DriveState::kSwitchOnDisabled);
  node.handle(rpdo1_frame(1, kCwShutdown, 0));
  node.handle(rpdo1_frame(1, kCwSwitchOn, 0));
  node.handle(rpdo1_frame(1, kCwEnableOperation, 0));
  EXPECT_EQ(node.state(), DriveState::kOperationEnabled);
  node.handle(rpdo1_frame(1, kCwQuickStop, 0));
  EXPECT_EQ(node.state(), DriveState::kQuickStopActive);
  node.handle(rpdo1_frame(1, kCwDisableVoltage, 0));
  EXPECT_EQ(node.state(), DriveState::kSwitchOnDisabled);
  // The motor ramps within its acceleration limit only when enabled.
  node.handle(rpdo1_frame(1, kCwShutdown, 0));
  node.handle(rpdo1_frame(1, kCwSwitchOn, 0));
  node.handle(rpdo1_frame(1, kCwEnableOperation, 100'000));
  node.step(100'000);  // 0.1 s at 200000 counts/s^2 -> 20000 counts/s
  EXPECT_DOUBLE_EQ(node.velocity_actual(), 20'000.0);
  EXPECT_DOUBLE_EQ(node.position_actual(), 1'000.0);
}


// The drive-side watchdog (0x1016 / 0x6007): set at bring-up; with the master
// gone the drives quick-stop on their own within the consumer time plus the
// ramp; a new master (the restarted daemon) re-arms it and drives again.
TEST(Cia402, DrivesStopOnTheirOwnWhenTheMasterDiesAndARestartedMasterDrivesAgain) {
  Bus bus;
  bus.run(40, {20'000, -20'000});
  ASSERT_TRUE(bus.master_.all_ready());
  for (auto& node : bus.nodes_) {
    EXPECT_EQ(node.consumer_heartbeat_time_us(), bus.master_.options().drive_heartbeat_consumer_us);
    EXPECT_EQ(node.abort_option(), AbortConnectionOption::kQuickStop);
  }
  bus.run(50, {20'000, -20'000});
  ASSERT_DOUBLE_EQ(bus.nodes_[0].velocity_actual(), 20'000.0);

  // Within the consumer time the drives keep going (a late heartbeat is no event) ...
  const std::int64_t consumer_us = bus.master_.options().drive_heartbeat_consumer_us;
  const int steps_in_consumer_time = static_cast<int>(consumer_us / 10'000) - 5;  // the last heartbeat may be 50 ms old
  EXPECT_TRUE(bus.run_without_master(steps_in_consumer_time).empty());
  EXPECT_DOUBLE_EQ(bus.nodes_[0].velocity_actual(), 20'000.0);
  // ... then a heartbeat event: EMCY 0x8130 and a quick stop at the drive's deceleration.
  const auto emcy = bus.run_without_master(10);
  EXPECT_EQ(emcy, (std::vector<std::uint16_t>{kEmcyHeartbeatError, kEmcyHeartbeatError}));
  for (auto& node : bus.nodes_) EXPECT_EQ(node.heartbeat_events(), 1u);
  bus.run_without_master(10);  // 20'000 counts/s at 200'000 counts/s^2: 100 ms
  for (auto& node : bus.nodes_) {
    EXPECT_EQ(node.velocity_actual(), 0.0);
    EXPECT_EQ(node.state(), DriveState::kSwitchOnDisabled);
  }
  // Stopped for good, with no master.
  bus.run_without_master(100);
  EXPECT_EQ(bus.nodes_[0].velocity_actual(), 0.0);
  EXPECT_EQ(bus.nodes_[0].heartbeat_events(), 1u);

  // A new master finds the drives Operational but disabled: configures them
  // again (watchdog included) and drives.
  bus.master_ = Cia402Master(Cia402Master::Options{});
  bus.run(60, {10'000, 10'000});
  EXPECT_TRUE(bus.master_.all_ready());
  EXPECT_DOUBLE_EQ(bus.nodes_[0].velocity_actual(), 10'000.0);
  EXPECT_EQ(bus.master_.nodes()[0].config_step, bus.master_.configuration().size());
}

// An NMT stop (sent by someone else): the drive stops and answers no SDO; the
// master brings it to pre-operational, configures and starts it, and drives.
TEST(Cia402, NodeStoppedByNmtIsBroughtBack) {
  Bus bus;
  bus.run(40, {5'000, 5'000});
  ASSERT_TRUE(bus.master_.all_ready());
  bus.nodes_[0].handle(nmt_frame(NmtCommand::kStop, 1));
  EXPECT_EQ(bus.nodes_[0].nmt_state(), NmtState::kStopped);
  bus.run(20, {5'000, 5'000});  // heartbeat: stopped -> the master reacts
  EXPECT_FALSE(bus.master_.all_ready());
  bus.run(60, {5'000, 5'000});
  EXPECT_TRUE(bus.master_.all_ready());
  EXPECT_EQ(bus.nodes_[0].nmt_state(), NmtState::kOperational);
  EXPECT_EQ(bus.nodes_[0].state(), DriveState::kOperationEnabled);
  EXPECT_DOUBLE_EQ(bus.nodes_[0].velocity_actual(), 5'000.0);
}

// The quick stop deceleration the master writes (0x6085) is what the drive ramps with.
TEST(Cia402, QuickStopUsesTheConfiguredDeceleration) {
  Bus bus;
  Cia402Master::Options o;
  o.quick_stop_deceleration = 1'000'000;  // five times the drive's own
  bus.master_ = Cia402Master(o);
  bus.run(40, {20'000, 20'000});
  bus.run(30, {20'000, 20'000});
  ASSERT_DOUBLE_EQ(bus.nodes_[0].velocity_actual(), 20'000.0);
  int steps = 0;
  for (; steps < 100 && bus.nodes_[0].velocity_actual() > 0.0; ++steps) bus.run_without_master(1);
  // 150 ms consumer time (minus up to 50 ms since the last heartbeat) + 20 ms ramp, in 10 ms steps.
  EXPECT_LE(steps, 18);
  EXPECT_GE(steps, 10);
}

TEST(Cia402, DriveRefusesWatchdogValuesOutOfRange) {
  DriveNode drive(DriveNode::Options{1, 100'000, 200'000.0});
  drive.step(0);  // boot-up: pre-operational, SDO accepted
  auto answer = [&](Frame f) {
    const auto out = drive.handle(f);
    EXPECT_EQ(out.size(), 1u);
    return read_sdo_response(out.at(0)).value();
  };
  EXPECT_TRUE(answer(sdo_write_frame(1, kObjAbortConnectionOption, 0, 7, 2)).abort);
  EXPECT_TRUE(answer(sdo_write_frame(1, kObjConsumerHeartbeatTime, 2, 0x7F0096, 4)).abort);  // wrong subindex
  EXPECT_TRUE(answer(sdo_write_frame(1, kObjQuickStopDeceleration, 0, 0, 4)).abort);
  EXPECT_EQ(drive.abort_option(), AbortConnectionOption::kFault);
  EXPECT_EQ(drive.consumer_heartbeat_time_us(), 0);
  EXPECT_FALSE(answer(sdo_write_frame(1, kObjConsumerHeartbeatTime, 1, 0x7F0096, 4)).abort);
  EXPECT_EQ(drive.consumer_heartbeat_time_us(), 150'000);
}

// What the simulator paces on: the watchdog's deadline is the last heartbeat
// of its producer (timed at the step after it came) plus the consumer time; a
// step at the deadline raises nothing, one later the event. Other nodes'
// heartbeats and a silenced drive have no deadline the simulator could hold.
TEST(Cia402, DriveTellsItsHeartbeatDeadline) {
  DriveNode drive(DriveNode::Options{1, 100'000, 200'000.0});
  drive.step(0);  // boot-up: pre-operational, SDO accepted
  EXPECT_FALSE(drive.consumes(heartbeat_frame(0x7F, NmtState::kOperational)));  // no watchdog yet
  ASSERT_EQ(drive.handle(sdo_write_frame(1, kObjConsumerHeartbeatTime, 1, 0x7F0096, 4)).size(), 1u);
  EXPECT_TRUE(drive.consumes(heartbeat_frame(0x7F, NmtState::kOperational)));
  EXPECT_FALSE(drive.consumes(heartbeat_frame(0x05, NmtState::kOperational)));
  EXPECT_FALSE(drive.consumes(sync_frame()));
  EXPECT_EQ(drive.heartbeat_deadline_us(), std::nullopt);  // not armed before the first heartbeat

  drive.handle(heartbeat_frame(0x7F, NmtState::kOperational));
  EXPECT_EQ(drive.heartbeat_deadline_us(), std::nullopt);  // heard, timed at the next step
  drive.step(10'000);
  EXPECT_EQ(drive.heartbeat_deadline_us(), 160'000);
  drive.handle(heartbeat_frame(0x05, NmtState::kOperational));  // another node's: no re-arm
  drive.step(160'000);
  EXPECT_EQ(drive.heartbeat_events(), 0u);
  EXPECT_EQ(drive.heartbeat_deadline_us(), 160'000);
  drive.step(160'001);
  EXPECT_EQ(drive.heartbeat_events(), 1u);
  EXPECT_EQ(drive.heartbeat_deadline_us(), std::nullopt);  // fired: disarmed until the next heartbeat

  drive.handle(heartbeat_frame(0x7F, NmtState::kOperational));
  drive.step(200'000);
  EXPECT_EQ(drive.heartbeat_deadline_us(), 350'000);
  // A reset of communication: booting, the node hears nothing before its
  // next step, so a clock held for its heartbeat would never get there.
  drive.handle(nmt_frame(NmtCommand::kResetCommunication, 1));
  EXPECT_EQ(drive.heartbeat_deadline_us(), std::nullopt);
  drive.step(250'000);  // boot-up sent; still armed
  EXPECT_EQ(drive.heartbeat_deadline_us(), 350'000);
  drive.set_silent(true);  // a cut cable: the watchdog fires, nothing may hold it
  EXPECT_EQ(drive.heartbeat_deadline_us(), std::nullopt);
}

}  // namespace
}  // namespace pex::canopen
