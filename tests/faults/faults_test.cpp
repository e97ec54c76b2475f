// Fault injection on the real daemons (ctest label `faults`): each case kills
// or breaks one part of a running set on a real LCM bus in a private network
// namespace, and checks the expectation against the simulator's truth
// (SIM_TRUTH), on the simulated clock (SIM_CLOCK).
//
//   kill -9 pex-base-driver while driving: the drives notice its heartbeat is
//   gone (CiA 301 consumer heartbeat 0x1016, set up by the driver at
//   bring-up) and quick-stop (0x6007): the robot stands within 300 ms of
//   simulated time. A restarted driver re-arms the watchdog and drives again.
//
//   kill -9 pex-base-driver under SLAM and restart: the new driver's odometry
//   starts again from (0, 0); SLAM takes it as an odometry reset (its heading
//   variance shrank) and its pose does not jump.
//
//   start order: each daemon of the set started last, after the others have
//   waited 5 simulated seconds without it (systemd gives no order between
//   them): the robot sets off. The mapper last deadlocked before SLAM
//   republished its particle set while the robot stands.
//
//   kill -9 pex-explorer mid-mission and restart: the mission is taken up from
//   its checkpoint (visited goals, distance, mission clock) and ends DONE.
//
//   kill -9 pex-polygon-mapper mid-mission (the set on SLAM, as on the robot)
//   and restart: the restarted mapper publishes the map of before from its
//   checkpoint at once, goes on from it with SLAM's next update (a resync: it
//   missed updates), and the mission ends DONE with the world mapped.
//
//   kill -9 pex-lidar-reader mid-mission: the explorer stops the robot once
//   no scan came for scan_timeout_ms (no driving blind) and says so in its
//   health (DEGRADED, "no laser scans"; the mapper too: "no LIDAR_SCAN for
//   3.0 s"); with the reader restarted the
//   mission goes on and ends DONE with the world mapped.
//
//   the laser stalls 15 s (connected, silent) or refuses connections 5 s
//   (SIM_FAULT, played by pex-sim over CoLa-A/TCP): the same stop, the
//   reader reconnects by itself, the mission ends DONE.
//
//   the laser goes blind 10 s (scans as ever, no echo on any beam): the
//   explorer and the mapper refuse them, the same stop, the map keeps its
//   walls, the mission ends DONE; the same with pex-slam in the set.
//
//   the scan telegrams held 0.8 s and then delivered at once, ten times while
//   the robot drives: each scan keeps its own time (no new device clock
//   offset), the map keeps its walls, the mission ends DONE.
//
//   the simulator frozen 5 s (SIGSTOP): every daemon on its clock says ERROR
//   and is OK again when it goes on; the mission ends DONE.
//
//   one absurd ODOMETRY (x = 1e300): SLAM refuses it with a count, no jump.
//
//   10 % of the LCM datagrams dropped (nftables in the private namespace):
//   the mission ends DONE with the world mapped.
#include <gtest/gtest.h>

#include <pex/explore_state_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/sim_fault_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <regex>
#include <filesystem>
#include <optional>

#include "exploration_set.hpp"
#include "map_score.hpp"
#include "harness.hpp"
#include "runtime/channels.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;
namespace ch = pex::runtime::channels;

namespace {

// BASE_CMDs of this test name it as their source.
bool drive_until(Bus& bus, double v, const std::function<bool()>& done) {
  return pex::testing::drive_until(bus, v, done, "faults_test");
}

// pex-sim's config on two_rooms (4 m of free floor ahead of the start pose), in `dir`.
std::string two_rooms_sim_config(const std::string& dir) {
  const std::string path = dir + "/sim.toml";
  write_file(path, with_key(read_file(sim_config_of("sim")), "world_file",
                            "\"" + source_path("worlds/two_rooms.wkt") + "\""));
  return path;
}

// What the bus carries of the truth and the clock.
struct Truth {
  std::vector<pex::pose_t> poses;
  std::int64_t clock_utime = 0;  // newest SIM_CLOCK
  explicit Truth(Bus& bus) {
    bus.on<pex::pose_t>(std::string(ch::kSimTruth), [this](const pex::pose_t& p) { poses.push_back(p); });
    bus.on<pex::sim_clock_t>(std::string(ch::kSimClock), [this](const pex::sim_clock_t& c) { clock_utime = c.utime; });
  }
  // Speed (m/s) over the `window_us` of simulated time up to truth pose `i`.
  double speed_at(std::size_t i, std::int64_t window_us = 100'000) const {
    if (i >= poses.size()) return 0.0;
    const auto& b = poses[i];
    for (std::size_t j = i + 1; j-- > 0;)
      if (b.utime - poses[j].utime >= window_us)
        return std::hypot(b.x - poses[j].x, b.y - poses[j].y) / (static_cast<double>(b.utime - poses[j].utime) * 1e-6);
    return 0.0;
  }
  // Speed (m/s) over the last `window_us` of simulated time.
  double speed(std::int64_t window_us = 100'000) const {
    return poses.empty() ? 0.0 : speed_at(poses.size() - 1, window_us);
  }
  // The utime of the first truth pose from index `from` on after which the
  // robot moves less than 2 mm in all the rest (at least 500 ms of it); -1 if none.
  std::int64_t stood_from(std::size_t from) const {
    for (std::size_t i = from; i < poses.size(); ++i) {
      if (poses.back().utime - poses[i].utime < 500'000) break;
      bool stands = true;
      for (std::size_t j = i + 1; j < poses.size() && stands; ++j)
        stands = std::hypot(poses[j].x - poses[i].x, poses[j].y - poses[i].y) < 0.002;
      if (stands) return poses[i].utime;
    }
    return -1;
  }
};

// After the laser went away at `fault_s` (simulated), with `first_after` the
// first truth pose after it: once the explorer and the mapper say they have
// no scans (the mapper's input timeout is 3 s), the robot stands.
void expect_standing_without_scans(ExplorationSet& set, const Truth& truth, std::size_t first_after, double fault_s) {
  const std::vector<pex::pose_t>& poses = truth.poses;
  // Statuses are stamped with the wall clock (they are published on it).
  const std::int64_t since_utime = std::chrono::duration_cast<std::chrono::microseconds>(
                                       std::chrono::system_clock::now().time_since_epoch())
                                       .count();
  auto degraded = [&](const char* name) {
    const auto it = set.bus().status().find(name);
    return it != set.bus().status().end() && it->second.state == pex::daemon_status_t::STATE_DEGRADED &&
           it->second.utime > since_utime;
  };
  // Health tells the truth: the explorer and the mapper cannot do their job
  // (the mapper after its input timeout, 3 s, and a heartbeat, 1 s of wall time).
  EXPECT_TRUE(set.spin_sim([&] { return degraded("explorer") && degraded("polygon_mapper"); }, 10.0))
      << "no DEGRADED status " << set.sim_seconds() - fault_s << " s after the laser went away";
  ASSERT_TRUE(set.state());
  EXPECT_NE(set.state()->status.find("no laser scan"), std::string::npos) << set.state()->status;
  ASSERT_GT(poses.size(), first_after + 10);
  // Standing: over the last 1.5 s the robot moved less than 2 cm.
  const auto& last = poses.back();
  for (std::size_t i = first_after; i < poses.size(); ++i) {
    if (last.utime - poses[i].utime > 1'500'000) continue;
    EXPECT_LT(std::hypot(last.x - poses[i].x, last.y - poses[i].y), 0.02)
        << "the robot drove on without scans (" << set.sim_seconds() - fault_s << " s after the fault)";
  }
}

}  // namespace

TEST(Faults, KilledBaseDriverStopsTheWheelsWithin300msAndARestartedOneDrivesAgain) {
  Bus bus;
  Truth truth(bus);
  const std::string dir = make_temp_dir("faults-driver");
  const std::string sim_config = two_rooms_sim_config(dir);
  auto sim = start_daemon("sim", dir, {}, sim_config);
  auto driver = start_daemon("base_driver", dir);
  std::vector<Process*> set = {sim.get(), driver.get()};
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok({"base_driver"}) && truth.poses.size() > 5; }, 30s))
      << logs_of(set);

  ASSERT_TRUE(drive_until(bus, 0.3, [&] { return truth.speed() > 0.25; })) << logs_of(set);

  // kill -9: no zero command, no NMT stop, nothing more from the driver.
  const std::int64_t kill_utime = truth.clock_utime;  // the test's newest clock: at or before the kill
  driver->kill_hard();
  const std::size_t first_after_kill = truth.poses.size();
  // The commands go on (the explorer does not know); 1.5 s of simulated time.
  ASSERT_TRUE(drive_until(bus, 0.3, [&] { return truth.clock_utime > kill_utime + 1'500'000; })) << logs_of(set);

  // When did the robot stand?
  const std::int64_t stop_utime = truth.stood_from(first_after_kill);
  ASSERT_GE(stop_utime, 0) << "the wheels kept turning after kill -9 of the driver";
  const double stop_ms = static_cast<double>(stop_utime - kill_utime) * 1e-3;
  EXPECT_LE(stop_ms, 300.0) << "stood " << stop_ms << " ms after the kill";
  std::printf("robot stood %.0f ms (simulated) after kill -9 of pex-base-driver\n", stop_ms);

  // A restarted driver configures the drives again and drives.
  driver = start_daemon("base_driver", dir);
  set = {sim.get(), driver.get()};
  EXPECT_TRUE(drive_until(bus, 0.3, [&] { return bus.all_ok({"base_driver"}) && truth.speed() > 0.25; }))
      << "no driving after the restart\n" << logs_of(set);
  for (Process* p : set) EXPECT_EQ(p->stop(5s), 0) << p->name() << "\n" << p->output();
  std::filesystem::remove_all(dir);
}

TEST(Faults, KilledLidarReaderStopsTheRobotAndTheMissionEndsDoneAfterItsRestart) {
  ExplorationSet set("faults-lidar", SetOptions{});
  Truth truth(set.bus());
  const std::vector<pex::pose_t>& poses = truth.poses;
  // Driving to a goal, well under way.
  ASSERT_TRUE(set.spin_sim(
      [&] { return set.phase() == pex::explore_state_t::PHASE_MOVING && truth.speed() > 0.2; }, 120.0))
      << set.report_with_logs();

  Process* reader = set.process("lidar_reader");
  ASSERT_NE(reader, nullptr);
  const double kill_s = set.sim_seconds();
  reader->kill_hard();
  const std::size_t first_after_kill = poses.size();
  expect_standing_without_scans(set, truth, first_after_kill, kill_s);

  // The reader back (systemd restarts it): the mission goes on to its end.
  set.restart("lidar_reader");
  expect_done_with_the_world_mapped(set);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

TEST(Faults, RestartedBaseDriverResetsOdometryAndSlamDoesNotJump) {
  Bus bus;
  Truth truth(bus);
  std::vector<pex::pose_t> slam_poses;
  bus.on<pex::pose_t>(std::string(ch::kSlamPose), [&](const pex::pose_t& p) { slam_poses.push_back(p); });
  const std::string dir = make_temp_dir("faults-odometry");
  const std::string sim_config = two_rooms_sim_config(dir);
  auto sim = start_daemon("sim", dir, {}, sim_config);
  auto reader = start_daemon("lidar_reader", dir);
  auto driver = start_daemon("base_driver", dir);
  auto slam = start_daemon("slam", dir);
  std::vector<Process*> set = {sim.get(), reader.get(), driver.get(), slam.get()};
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok({"base_driver", "slam"}) && !slam_poses.empty(); }, 30s))
      << logs_of(set);
  const pex::pose_t truth_start = truth.poses.back();
  const pex::pose_t slam_start = slam_poses.back();
  auto travelled = [&] { return std::hypot(truth.poses.back().x - truth_start.x, truth.poses.back().y - truth_start.y); };
  ASSERT_TRUE(drive_until(bus, 0.3, [&] { return travelled() > 1.0; })) << logs_of(set);

  driver->kill_hard();
  bus.spin_until([&] { return truth.speed() < 0.01; }, 10s);  // the drives stop on their own
  driver = start_daemon("base_driver", dir);
  set = {sim.get(), reader.get(), driver.get(), slam.get()};
  ASSERT_TRUE(drive_until(bus, 0.3, [&] { return bus.all_ok({"base_driver"}) && travelled() > 2.0; })) << logs_of(set);
  bus.spin_until([&] { return false; }, 1500ms);  // statuses with the final counters

  // SLAM moved as far as the robot did, with no jump on the way.
  const pex::pose_t& slam_end = slam_poses.back();
  const double slam_moved = std::hypot(slam_end.x - slam_start.x, slam_end.y - slam_start.y);
  EXPECT_NEAR(slam_moved, travelled(), 0.15) << "SLAM moved " << slam_moved << " m, the robot " << travelled() << " m";
  double largest_step = 0.0;
  for (std::size_t i = 1; i < slam_poses.size(); ++i)
    largest_step = std::max(largest_step, std::hypot(slam_poses[i].x - slam_poses[i - 1].x,
                                                     slam_poses[i].y - slam_poses[i - 1].y));
  EXPECT_LT(largest_step, 0.15) << "the SLAM pose jumped";
  EXPECT_EQ(counter_of(bus.status().at("slam"), "odometry_resets"), 1);
  for (Process* p : set) EXPECT_EQ(p->stop(5s), 0) << p->name() << "\n" << p->output();
  std::filesystem::remove_all(dir);
}

TEST(Faults, KilledExplorerTakesItsMissionUpFromTheCheckpoint) {
  const std::string dir = make_temp_dir("faults-explorer-state");
  const std::string checkpoint = dir + "/mission.txt";
  const std::string trails = dir + "/trails.bin";
  ExplorationSet set("faults-explorer", {.explorer_keys = {{"checkpoint_file", "\"" + checkpoint + "\""},
                                                           {"trail_checkpoint_file", "\"" + trails + "\""},
                                                           {"checkpoint_period_s", "0.5"}}});
  // Mid-mission: the robot some metres on its way to a goal, a checkpoint
  // written meanwhile. (Progress is measured in metres, not goals: a goal
  // whose frontier the laser explores before the robot gets there is left as
  // seen, not reached, so a mission may end before any goal is "reached".)
  ASSERT_TRUE(set.spin_sim(
      [&] {
        return mission_finished(set.phase()) ||
               (set.state() && set.state()->distance_travelled_m >= 3.0 &&
                set.phase() == pex::explore_state_t::PHASE_MOVING);
      },
      300.0))
      << set.report_with_logs();
  set.spin_sim([] { return false; }, 1.0);
  ASSERT_FALSE(mission_finished(set.phase())) << "the mission ended before the fault\n" << set.report_with_logs();
  const pex::explore_state_t before = *set.state();
  set.process("explorer")->kill_hard();
  set.restart("explorer");
  // The restarted explorer's first states carry the mission on.
  const double restarted_at = set.sim_seconds();
  ASSERT_TRUE(set.spin_sim([&] { return set.state() && set.state()->utime > before.utime + 1'000'000 &&
                                        set.sim_seconds() > restarted_at + 2.0; },
                           60.0))
      << set.report_with_logs();
  const pex::explore_state_t after = *set.state();
  EXPECT_GE(after.goals_reached, before.goals_reached) << "visited goals lost in the restart";
  EXPECT_GE(after.distance_travelled_m, before.distance_travelled_m - 0.5) << "the travelled distance restarted";
  EXPECT_GE(after.mission_time_s, before.mission_time_s) << "the mission clock restarted";
  // And the way the robot drove, which tight plans and the way home follow.
  EXPECT_NE(set.process("explorer")->output().find("trails restored from " + trails), std::string::npos)
      << set.process("explorer")->output();
  expect_done_with_the_world_mapped(set);
  EXPECT_GT(set.bus().status().at("explorer").ncounters, 0);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(dir);
}

TEST(Faults, KilledMapperPublishesItsMapFromTheCheckpointAndGoesOnWithSlam) {
  const std::string checkpoint = make_temp_dir("faults-mapper-state") + "/map.bin";
  ExplorationSet set("faults-mapper",
                     {.slam = true,
                      .mapper_keys = {{"checkpoint_file", "\"" + checkpoint + "\""}, {"checkpoint_period_s", "0.5"}}});
  std::vector<pex::polygon_map_t> maps;
  set.bus().on<pex::polygon_map_t>(std::string(ch::kMap), [&](const pex::polygon_map_t& m) { maps.push_back(m); });
  // Most of the world mapped (more than any one scan sees), a checkpoint after it.
  ASSERT_TRUE(set.spin_sim([&] { return !maps.empty() && maps.back().free_area_m2 > 60.0; }, 300.0))
      << set.report_with_logs();
  set.spin_sim([] { return false; }, 1.5);
  const pex::polygon_map_t before = maps.back();
  set.process("polygon_mapper")->kill_hard();
  const std::size_t maps_before_restart = maps.size();
  set.restart("polygon_mapper");
  ASSERT_TRUE(set.spin_sim([&] { return maps.size() > maps_before_restart; }, 30.0)) << set.report_with_logs();
  // The restarted mapper's first map is the map of before (up to the scans of
  // the last checkpoint period), not one scan's.
  const pex::polygon_map_t first = maps[maps_before_restart];
  EXPECT_GT(first.free_area_m2, 0.97 * before.free_area_m2)
      << "the map after the restart has " << first.free_area_m2 << " m^2, before it " << before.free_area_m2;
  expect_done_with_the_world_mapped(set);
  const auto& status = set.bus().status().at("polygon_mapper");
  EXPECT_GE(counter_of(status, "slam_resyncs"), 1) << "the restarted mapper followed parents it never saw";
  EXPECT_EQ(counter_of(status, "slam_epoch_changes"), 0);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(std::filesystem::path(checkpoint).parent_path());
}

// The laser misbehaves on its own (pex-sim plays it over CoLa-A/TCP): the
// robot stands while no scan comes, the reader reconnects by itself once the
// device is back, and the mission ends DONE.
void laser_fault_then_done(std::int8_t fault, double duration_s, bool reader_reconnects = true, bool slam = false) {
  ExplorationSet set("faults-laser", {.speed = 2.0, .slam = slam});
  Truth truth(set.bus());
  ASSERT_TRUE(set.spin_sim(
      [&] { return set.phase() == pex::explore_state_t::PHASE_MOVING && truth.speed() > 0.2; }, 120.0))
      << set.report_with_logs();
  pex::sim_fault_t msg{};
  msg.utime = set.clock()->utime;
  msg.fault = fault;
  msg.duration_s = duration_s;
  msg.source = "faults_test";
  const double fault_s = set.sim_seconds();
  const std::size_t first_after = truth.poses.size();
  set.bus().publish(std::string(ch::kSimFault), msg);
  expect_standing_without_scans(set, truth, first_after, fault_s);
  // Standing for the whole fault: from 1 s after it began to its end, less than 5 cm.
  const std::size_t standing_from = truth.poses.size();
  set.spin_sim([&] { return set.sim_seconds() > fault_s + duration_s; }, duration_s + 5.0);
  double wandered = 0.0;
  for (std::size_t i = standing_from; i < truth.poses.size(); ++i) {
    if (static_cast<double>(truth.poses[i].utime - truth.poses[standing_from].utime) * 1e-6 > duration_s - 5.0) break;
    wandered = std::max(wandered, std::hypot(truth.poses[i].x - truth.poses[standing_from].x,
                                             truth.poses[i].y - truth.poses[standing_from].y));
  }
  EXPECT_LT(wandered, 0.05) << "the robot moved during the laser fault";
  expect_done_with_the_world_mapped(set);
  if (reader_reconnects) {
    EXPECT_GE(counter_of(set.bus().status().at("lidar_reader"), "disconnects"), 1);
  } else {
    // The device streamed on: the scans came, and the explorer and the
    // mapper refused them (min_scan_returns, min_returns), so the map kept
    // its walls (expect_done_with_the_world_mapped scores it against them).
    EXPECT_LT(counter_of(set.bus().status().at("lidar_reader"), "disconnects"), 1);  // -1: never counted
    EXPECT_GE(set.bus().status().at("explorer").msgs_rejected, 10);
    EXPECT_GE(set.bus().status().at("polygon_mapper").msgs_rejected, 10);
  }
  EXPECT_EQ(counter_of(set.bus().status().at("sim"), "laser_faults"), 1);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

TEST(Faults, LaserStreamStalled15sTheRobotStandsAndTheMissionEndsDone) {
  laser_fault_then_done(pex::sim_fault_t::FAULT_LASER_STALL, 15.0);
}

TEST(Faults, LaserRefusingConnections5sTheRobotStandsAndTheMissionEndsDone) {
  laser_fault_then_done(pex::sim_fault_t::FAULT_LASER_REFUSE, 5.0);
}

TEST(Faults, LaserBlind10sTheRobotStandsTheMapKeepsItsWallsAndTheMissionEndsDone) {
  laser_fault_then_done(pex::sim_fault_t::FAULT_LASER_BLIND, 10.0, false);
}

// The mapper killed while a sector of the laser is blind, and restarted: the
// blind beams are not in its checkpoint. The restored map's walls stop them
// (no_return_stops_at_walls), and none gives free space before it has
// returned an echo (no_free_space_before_first_echo), so the map keeps its
// walls; the mapper finds the sector blind again against them and says so,
// and the mission ends DONE with the world mapped. (With the first-echo rule
// off it passed too, 2 runs of 2: the walls about the robot were mapped.)
TEST(Faults, KilledMapperWithASectorBlindCarvesNothingAfterItsRestart) {
  const std::string checkpoint = make_temp_dir("faults-mapper-blind-state") + "/map.bin";
  ExplorationSet set("faults-mapper-blind",
                     {.speed = 2.0,
                      .mapper_keys = {{"checkpoint_file", "\"" + checkpoint + "\""}, {"checkpoint_period_s", "0.5"}}});
  ASSERT_TRUE(set.spin_sim([&] { return set.map() && set.map()->free_area_m2 > 60.0; }, 300.0))
      << set.report_with_logs();
  pex::sim_fault_t msg{};
  msg.utime = set.clock()->utime;
  msg.fault = pex::sim_fault_t::FAULT_LASER_BLIND_SECTOR;
  msg.duration_s = 3600.0;
  msg.sector_from_rad = 0.4;
  msg.sector_to_rad = 1.2;
  msg.source = "faults_test";
  set.bus().publish(std::string(ch::kSimFault), msg);
  auto blind_beams = [&] { return counter_of(set.bus().status().at("polygon_mapper"), "blind_beams"); };
  ASSERT_TRUE(set.spin_sim([&] { return blind_beams() >= 46; }, 60.0)) << set.report_with_logs();
  set.spin_sim([] { return false; }, 1.5);  // a checkpoint with the sector blind
  set.process("polygon_mapper")->kill_hard();
  set.restart("polygon_mapper");
  expect_done_with_the_world_mapped(set);
  const auto& mapper = set.bus().status().at("polygon_mapper");
  EXPECT_GE(counter_of(mapper, "blind_onsets"), 1) << "the restarted mapper never found the sector blind";
  EXPECT_GE(counter_of(mapper, "blind_beams"), 46);
  EXPECT_EQ(+mapper.state, +pex::daemon_status_t::STATE_DEGRADED);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(std::filesystem::path(checkpoint).parent_path());
}

// The laser's window dirty (pex-sim's FAULT_LASER_CONTAMINATED: the device's
// contamination measurement, CoLa "sRN LCMstate", answers 2 = error): the
// reader asks it every contamination_poll_ms (10 s) and says so, DEGRADED
// with the level, while the scans go on; the window clean again, OK.
TEST(Faults, ADirtyLaserWindowMakesTheReaderDegradedUntilItIsClean) {
  ExplorationSet set("faults-dirty", {.speed = 2.0, .held_back = {"base_driver", "polygon_mapper", "explorer"}});
  auto reader_in = [&](std::int8_t state) {
    const auto it = set.bus().status().find("lidar_reader");
    return it != set.bus().status().end() && it->second.state == state;
  };
  const std::string scans_channel(ch::kLidarScan);
  ASSERT_TRUE(set.bus().spin_until(
      [&] { return reader_in(pex::daemon_status_t::STATE_OK) && set.bus().count(scans_channel) > 0; }, 60s))
      << set.report_with_logs();
  ASSERT_TRUE(set.spin_sim(
      [&] { return counter_of(set.bus().status().at("lidar_reader"), "contamination_level") == 0; }, 15.0))
      << "the reader never read the window's contamination\n" << set.report_with_logs();
  pex::sim_fault_t msg{};
  msg.utime = set.clock()->utime;
  msg.fault = pex::sim_fault_t::FAULT_LASER_CONTAMINATED;
  msg.duration_s = 30.0;
  msg.contamination_level = 2;
  msg.source = "faults_test";
  const double fault_s = set.sim_seconds();
  set.bus().publish(std::string(ch::kSimFault), msg);
  // Within one poll period (10 s) and a heartbeat.
  EXPECT_TRUE(set.spin_sim([&] { return reader_in(pex::daemon_status_t::STATE_DEGRADED); }, 15.0))
      << set.report_with_logs();
  EXPECT_EQ(counter_of(set.bus().status().at("lidar_reader"), "contamination_level"), 2);
  EXPECT_NE(set.process("lidar_reader")->output().find("lens contamination error (LCMstate 2)"), std::string::npos)
      << set.process("lidar_reader")->output();
  const int scans_degraded = set.bus().count(scans_channel);
  set.spin_sim([] { return false; }, 2.0);
  EXPECT_GT(set.bus().count(scans_channel), scans_degraded + 25) << "the scans stopped with the window dirty";
  EXPECT_TRUE(reader_in(pex::daemon_status_t::STATE_DEGRADED));
  // The fault over (30 s), the next poll reads a clean window.
  EXPECT_TRUE(set.spin_sim([&] { return reader_in(pex::daemon_status_t::STATE_OK); }, 45.0))
      << set.report_with_logs();
  EXPECT_GT(set.sim_seconds(), fault_s + 30.0) << "OK again while the window was still dirty";
  EXPECT_EQ(counter_of(set.bus().status().at("lidar_reader"), "contamination_level"), 0);
  EXPECT_LT(counter_of(set.bus().status().at("lidar_reader"), "disconnects"), 1);  // -1: never counted
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

// The same on SLAM, as on the robot: SLAM gets the blind scans too (it
// takes no-echo beams as nothing), and the mapper, which refuses them,
// still follows SLAM's updates after the fault.
TEST(Faults, LaserBlind10sOnSlamTheRobotStandsAndTheMissionEndsDone) {
  laser_fault_then_done(pex::sim_fault_t::FAULT_LASER_BLIND, 10.0, false, true);
}

// The scan telegrams wait and then come at once (the reader's computer
// stalled, a switch held them): 0.8 s of scans, short of the reader's stale
// timeout, again and again while the robot drives. Each scan keeps the time
// it was taken: cola::DeviceClock takes the late ones as outliers, not as a
// new offset (starting afresh on them stamped a whole backlog with the time
// it was read: the scans of a turning robot drawn at the pose of the stall's
// end). The map keeps its walls and the mission ends DONE.
TEST(Faults, LaserTelegramsHeldAndDeliveredAtOnceKeepTheirTimesAndTheMapItsWalls) {
  ExplorationSet set("faults-held", {.speed = 2.0});
  Truth truth(set.bus());
  int held = 0;
  while (held < 10 && !mission_finished(set.phase())) {
    const bool moving = set.spin_sim(
        [&] {
          return mission_finished(set.phase()) ||
                 (set.phase() == pex::explore_state_t::PHASE_MOVING && truth.speed() > 0.2);
        },
        120.0);
    ASSERT_TRUE(moving) << set.report_with_logs();
    if (mission_finished(set.phase())) break;
    pex::sim_fault_t msg{};
    msg.utime = set.clock()->utime;
    msg.fault = pex::sim_fault_t::FAULT_LASER_HELD;
    msg.duration_s = 0.8;
    msg.source = "faults_test";
    const double fault_s = set.sim_seconds();
    set.bus().publish(std::string(ch::kSimFault), msg);
    ++held;
    // The stream back and the robot on its way before the next.
    set.spin_sim([&] { return false; }, 3.0);
    ASSERT_GT(set.sim_seconds(), fault_s + 2.9);
  }
  ASSERT_GE(held, 5) << "the mission ended before the faults";
  expect_done_with_the_world_mapped(set);
  const auto& reader = set.bus().status().at("lidar_reader");
  EXPECT_EQ(counter_of(set.bus().status().at("sim"), "laser_faults"), held);
  EXPECT_GE(counter_of(reader, "device_clock_outliers"), held) << "no scan came late: the fault did not hold them";
  EXPECT_EQ(counter_of(reader, "device_clock_resets"), 0);
  EXPECT_LT(counter_of(reader, "disconnects"), 1);  // -1: never counted; the stream went on
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

// Part of the laser's window covered (a cable hanging in front of it): the
// beams of a sector have no echo for the rest of the mission, the others see.
// The scans have returns enough to be taken; each blind beam would be free
// space for 4 m through the walls beside the robot. They stop at the walls
// the map holds (no_return_stops_at_walls, in the mapper and the explorer's
// live view), so the map keeps its walls; once found blind they give no free
// space at all, so no wall the map has not seen yet is carved through either;
// the scan guard reads the planning map's walls for them (guard_map_walls_m),
// so the robot touches none of them; the mission ends DONE, and the mapper
// and explorer count the beams.
void laser_blind_in_a_sector_then_done(bool slam) {
  ExplorationSet set("faults-sector", {.speed = 2.0, .slam = slam});
  std::vector<pex::polygon_map_t> maps;
  set.bus().on<pex::polygon_map_t>(std::string(ch::kMap), [&](const pex::polygon_map_t& m) { maps.push_back(m); });
  // Much of the world seen first (60 of its 82.6 m^2 of floor): many of its
  // walls are in the map, some are not yet (the box's and the pillar's far
  // sides, the right room's corners). The blind beams must carve through
  // neither: the mapper finds them blind against the walls it holds
  // (mapping::BlindBeams), and from then on they give no free space.
  ASSERT_TRUE(set.spin_sim([&] { return !maps.empty() && maps.back().free_area_m2 > 60.0; }, 300.0))
      << set.report_with_logs();
  pex::sim_fault_t msg{};
  msg.utime = set.clock()->utime;
  msg.fault = pex::sim_fault_t::FAULT_LASER_BLIND_SECTOR;
  msg.duration_s = 3600.0;
  msg.sector_from_rad = 0.4;  // ahead to the left, 46 degrees wide
  msg.sector_to_rad = 1.2;
  msg.source = "faults_test";
  set.bus().publish(std::string(ch::kSimFault), msg);
  expect_done_with_the_world_mapped(set);
  EXPECT_EQ(counter_of(set.bus().status().at("sim"), "laser_faults"), 1);
  EXPECT_GT(counter_of(set.bus().status().at("polygon_mapper"), "no_return_beams_stopped"), 100);
  // The mapper found the sector blind once and for good (the fault lasts),
  // at least half of its 92 beams. Without it (blind_after_stopped_scans = 0)
  // this test failed in 11 of 20 runs from 60 m^2 (docs/mapping.md); from
  // 72 m^2 it failed once in CI with a collision beside the pillar.
  EXPECT_EQ(counter_of(set.bus().status().at("polygon_mapper"), "blind_onsets"), 1);
  EXPECT_GE(counter_of(set.bus().status().at("polygon_mapper"), "blind_beams"), 46);
  // And says so: DEGRADED, with where (the sector is 0.4..1.2 rad).
  EXPECT_EQ(+set.bus().status().at("polygon_mapper").state, +pex::daemon_status_t::STATE_DEGRADED);
  EXPECT_NE(set.process("polygon_mapper")->output().find("state DEGRADED: laser blind on"), std::string::npos)
      << set.process("polygon_mapper")->output();
  EXPECT_GT(counter_of(set.bus().status().at("explorer"), "guard_map_wall_beams"), 100);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

TEST(Faults, LaserBlindInASectorTheMapKeepsItsWallsAndTheMissionEndsDone) { laser_blind_in_a_sector_then_done(false); }

// The same on SLAM: each particle's map stops the blind beams at its own
// walls (ParticleMaps::update), and the mapper publishes the best one's.
TEST(Faults, LaserBlindInASectorOnSlamTheMapKeepsItsWallsAndTheMissionEndsDone) {
  laser_blind_in_a_sector_then_done(true);
}

// The same sector blind before the mapper's first scan (the window covered
// when the robot boots, or a mapper restarted while a sector stays blind):
// no wall the map holds to find its beams blind against, and each would give
// free space for 4 m through the walls about the start. A beam that has not
// returned an echo since the mapper started gives no free space
// ([scan] no_free_space_before_first_echo), so the map keeps its walls and
// the mission ends DONE with the world mapped.
void laser_blind_from_the_start_then_done(bool slam) {
  ExplorationSet set("faults-sector-start", {.speed = 2.0, .slam = slam, .held_back = {"polygon_mapper", "explorer"}});
  ASSERT_TRUE(set.bus().spin_until([&] { return set.bus().status().count("sim") && set.sim_seconds() > 0.0; }, 60s))
      << set.report_with_logs();
  pex::sim_fault_t msg{};
  msg.utime = set.clock()->utime;
  msg.fault = pex::sim_fault_t::FAULT_LASER_BLIND_SECTOR;
  msg.duration_s = 3600.0;
  // Behind to the right, 74 degrees wide: from the first scan on it points
  // at the outer wall 2-2.7 m from the start, and each blind beam would give
  // up to 2 m of free space beyond the world before any wall is mapped there.
  msg.sector_from_rad = -2.3;
  msg.sector_to_rad = -1.0;
  msg.source = "faults_test";
  set.bus().publish(std::string(ch::kSimFault), msg);
  ASSERT_TRUE(set.bus().spin_until(
      [&] { return counter_of(set.bus().status().at("sim"), "laser_faults") == 1; }, 60s))
      << set.report_with_logs();
  // Only now the mapper (and the explorer, which waits for a map): its every
  // scan is blind in the sector.
  set.start("polygon_mapper");
  set.start("explorer");
  expect_done_with_the_world_mapped(set);
  // The sector's beams (1.3 rad of 0.5-degree beams: 148) never echoed; once
  // other beams had mapped the walls there they were found blind, and said so.
  const auto& mapper = set.bus().status().at("polygon_mapper");
  EXPECT_GE(counter_of(mapper, "never_echoed_beams"), 140);
  EXPECT_GE(counter_of(mapper, "blind_beams"), 74);
  EXPECT_EQ(+mapper.state, +pex::daemon_status_t::STATE_DEGRADED);
  EXPECT_NE(set.process("polygon_mapper")->output().find("state DEGRADED: laser blind on"), std::string::npos)
      << set.process("polygon_mapper")->output();
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

TEST(Faults, LaserBlindInASectorFromTheStartTheMapKeepsItsWallsAndTheMissionEndsDone) {
  laser_blind_from_the_start_then_done(false);
}

// On SLAM: the mapper joins a filter that has run since the start (as after a
// restart of the mapper), every particle's map without the sector's space.
TEST(Faults, LaserBlindInASectorFromTheStartOnSlamTheMapKeepsItsWallsAndTheMissionEndsDone) {
  laser_blind_from_the_start_then_done(true);
}

// Any start order brings the mission up (systemd orders none of the daemons
// after another, and restarts any of them alone): each daemon of the set
// (with SLAM, as on the robot) started last, after the others have said they
// are up and, when the simulator runs, waited 5 simulated seconds without it.
// The mapper last is the case that deadlocked (SLAM updates only when the
// robot moves; the robot waits for a map): with republish_period_s = 0 it
// fails.
class StartOrder : public ::testing::TestWithParam<std::string> {};

TEST_P(StartOrder, TheDaemonStartedLastBringsTheMissionUp) {
  const std::string last = GetParam();
  ExplorationSet set("faults-order-" + last, {.speed = 2.0, .slam = true, .held_back = {last}});
  std::vector<std::string> others;
  for (const std::string& name : kAllDaemons)
    if (name != last) others.push_back(name);
  auto heard_from = [&](const std::vector<std::string>& names) {
    for (const auto& name : names)
      if (!set.bus().status().count(name)) return false;
    return true;
  };
  ASSERT_TRUE(set.bus().spin_until([&] { return heard_from(others); }, 60s)) << set.report_with_logs();
  if (last != "sim") {
    ASSERT_TRUE(set.spin_sim([] { return false; }, 5.0) || set.sim_seconds() >= 5.0) << set.report_with_logs();
    ASSERT_TRUE(set.truth() && set.first_truth());
    EXPECT_LT(std::hypot(set.truth()->x - set.first_truth()->x, set.truth()->y - set.first_truth()->y), 0.05)
        << "the robot moved without " << last;
  }
  set.start(last);
  // The robot sets off: 0.3 m from where it stood within 30 simulated seconds.
  auto moved = [&] {
    return set.truth() && set.first_truth() &&
           std::hypot(set.truth()->x - set.first_truth()->x, set.truth()->y - set.first_truth()->y) > 0.3;
  };
  ASSERT_TRUE(set.bus().spin_until([&] { return set.sim_seconds() > 0.0; }, 60s)) << set.report_with_logs();
  EXPECT_TRUE(set.spin_sim(moved, 30.0)) << "the robot never set off with " << last << " started last\n"
                                         << set.report_with_logs();
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

INSTANTIATE_TEST_SUITE_P(Faults, StartOrder, ::testing::ValuesIn(kAllDaemons),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param + "_last"; });

// The simulator frozen (SIGSTOP) for 5 s: the whole world stops, simulated
// time too. Every daemon on the simulator's clock says it cannot do its job
// (ERROR: no SIM_CLOCK) instead of OK; once the simulator goes on, every
// daemon is OK again without a restart, and the mission ends DONE with the
// world mapped and nothing beyond it.
TEST(Faults, FrozenSimulatorEveryDaemonSaysSoAndTheMissionGoesOnAfterIt) {
  ExplorationSet set("faults-freeze", {.speed = 2.0, .slam = true});
  Truth truth(set.bus());
  ASSERT_TRUE(set.spin_sim(
      [&] { return set.phase() == pex::explore_state_t::PHASE_MOVING && truth.speed() > 0.2; }, 120.0))
      << set.report_with_logs();
  const std::vector<std::string> on_sim_clock = {"lidar_reader", "base_driver", "slam", "polygon_mapper", "explorer"};
  auto all_in = [&](std::int8_t state) {
    for (const auto& name : on_sim_clock) {
      const auto it = set.bus().status().find(name);
      if (it == set.bus().status().end() || it->second.state != state) return false;
    }
    return true;
  };
  Process* sim = set.process("sim");
  ASSERT_NE(sim, nullptr);
  const auto frozen_at = std::chrono::steady_clock::now();
  ASSERT_EQ(::kill(sim->pid(), SIGSTOP), 0);
  const bool said_so = set.bus().spin_until([&] { return all_in(pex::daemon_status_t::STATE_ERROR); }, 20s);
  // The fault lasts 5 s (wall: a frozen simulator has no time of its own).
  set.bus().spin_until([&] { return std::chrono::steady_clock::now() - frozen_at > 5s; }, 10s);
  ASSERT_EQ(::kill(sim->pid(), SIGCONT), 0);
  EXPECT_TRUE(said_so) << "not every daemon said ERROR while the simulator was frozen\n" << set.report_with_logs();
  EXPECT_TRUE(set.bus().spin_until([&] { return all_in(pex::daemon_status_t::STATE_OK); }, 30s))
      << "not every daemon OK again after the simulator went on\n" << set.report_with_logs();
  expect_done_with_the_world_mapped(set);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

// Absurd ODOMETRY on the bus mid-mission, as a broken driver or a bit flip
// could send: one reading at x = 1e300, and later one 5 m from the robot's
// newest reading 10 ms after it. SLAM refuses the first and holds the second
// (counted: msgs_rejected, odometry_impossible_steps), and its pose does not
// move; the mission ends DONE with the world mapped and nothing beyond it.
TEST(Faults, AbsurdOdometryIsRefusedAndSlamDoesNotJump) {
  ExplorationSet set("faults-absurd-odometry", {.speed = 2.0, .slam = true});
  Truth truth(set.bus());
  std::vector<pex::pose_t> slam_poses;
  set.bus().on<pex::pose_t>(std::string(ch::kSlamPose), [&](const pex::pose_t& p) { slam_poses.push_back(p); });
  std::optional<pex::odometry_t> odometry;
  set.bus().on<pex::odometry_t>(std::string(ch::kOdometry), [&](const pex::odometry_t& o) { odometry = o; });
  ASSERT_TRUE(set.spin_sim(
      [&] { return set.phase() == pex::explore_state_t::PHASE_MOVING && truth.speed() > 0.2 && odometry; }, 120.0))
      << set.report_with_logs();
  const std::size_t first_after = slam_poses.size();
  // Stamped between the driver's readings (50 Hz).
  pex::odometry_t absurd = *odometry;
  absurd.utime = odometry->utime + 10'000;
  absurd.x = 1e300;
  set.bus().publish(std::string(ch::kOdometry), absurd);
  set.spin_sim([] { return false; }, 1.0);
  pex::odometry_t jump = *odometry;  // the newest real reading, its covariance (no new integrator)
  jump.utime = odometry->utime + 10'000;
  jump.x += 5.0 * std::cos(jump.theta);
  jump.y += 5.0 * std::sin(jump.theta);
  set.bus().publish(std::string(ch::kOdometry), jump);
  const double sent_s = set.sim_seconds();
  ASSERT_TRUE(set.spin_sim([&] { return set.sim_seconds() > sent_s + 3.0; }, 10.0));
  const auto& status = set.bus().status().at("slam");
  EXPECT_GE(status.msgs_rejected, 2) << "the absurd readings were not refused";
  EXPECT_GE(counter_of(status, "odometry_impossible_steps"), 1) << "the 5 m step was not held";
  ASSERT_GT(slam_poses.size(), first_after + 10);
  double largest_step = 0.0;
  for (std::size_t i = std::max<std::size_t>(first_after, 1); i < slam_poses.size(); ++i)
    largest_step = std::max(largest_step, std::hypot(slam_poses[i].x - slam_poses[i - 1].x,
                                                     slam_poses[i].y - slam_poses[i - 1].y));
  EXPECT_LT(largest_step, 0.15) << "the SLAM pose jumped";
  expect_done_with_the_world_mapped(set);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

// 10 % of the LCM datagrams lost (a kernel firewall rule in the test's
// private namespace drops every tenth packet to the LCM group at random, for
// every daemon and the test alike): the mission ends DONE with the world
// mapped, nothing beyond it, no collision.
TEST(Faults, TenPercentOfLcmMessagesDroppedTheMissionEndsDone) {
  const std::string table = "pex_faults_drop";
  auto nft = [](std::vector<std::string> args) {
    args.insert(args.begin(), "/usr/sbin/nft");
    return run_to_completion(args, 10s);
  };
  nft({"delete", "table", "inet", table});  // left over from an earlier run, if any
  ASSERT_EQ(nft({"add", "table", "inet", table}).exit_code, 0);
  ASSERT_EQ(nft({"add", "chain", "inet", table, "in", "{ type filter hook input priority 0; }"}).exit_code, 0);
  const RunResult rule = nft({"add", "rule", "inet", table, "in", "ip", "daddr", "239.255.76.67", "udp", "dport",
                              "7667", "numgen", "random", "mod", "10", "0", "counter", "drop"});
  ASSERT_EQ(rule.exit_code, 0) << rule.output;
  {
    ExplorationSet set("faults-lcm-drop", {.speed = 2.0, .slam = true});
    expect_done_with_the_world_mapped(set);
  set.stop_all();
    set.clean_up(::testing::Test::HasFailure());
  }
  // The fault was real: thousands of datagrams dropped.
  const RunResult listed = nft({"list", "table", "inet", table});
  nft({"delete", "table", "inet", table});
  std::smatch m;
  ASSERT_TRUE(std::regex_search(listed.output, m, std::regex("packets ([0-9]+)"))) << listed.output;
  const long dropped = std::stol(m[1]);
  std::printf("LCM datagrams dropped: %ld\n", dropped);
  EXPECT_GT(dropped, 1000);
}

// The wall clock stepped back an hour under pex-base-driver on the system
// clock, as on the robot (an NTP step; libfaketime shifts CLOCK_REALTIME for
// that process alone, FAKETIME_DONT_FAKE_MONOTONIC=1 as the kernel would):
// the driver's timeouts and heartbeat run on the monotonic clock, so it drives
// on while commands come, without a spurious drive watchdog stop, and stops
// the wheels on a stale command as always. With the monotonic clock shifted
// too (what a driver on the wall clock would see) the drives' watchdog stops
// the robot while it is commanded, and this test fails.
TEST(Faults, WallClockSteppedBackAnHourTheDriverDrivesOnAndStopsOnAStaleCommand) {
  Bus bus;
  Truth truth(bus);
  const std::string dir = make_temp_dir("faults-ntp");
  const std::string sim_config = two_rooms_sim_config(dir);
  auto sim = start_daemon("sim", dir, {}, sim_config);
  const std::string offset_file = dir + "/wall_clock_offset";
  write_file(offset_file, "+0\n");
  const std::string driver_config = write_config(
      dir, "base_driver", with_key(read_file(sim_config_of("base_driver")), "clock", "\"system\""));
  // The driver alone runs under libfaketime (the environment is inherited at exec).
  ::setenv("LD_PRELOAD", PEX_LIBFAKETIME, 1);
  ::setenv("FAKETIME_TIMESTAMP_FILE", offset_file.c_str(), 1);
  ::setenv("FAKETIME_NO_CACHE", "1", 1);
  ::setenv("FAKETIME_DONT_FAKE_MONOTONIC", "1", 1);
  auto driver = start_daemon("base_driver", dir, {}, driver_config);
  for (const char* name : {"LD_PRELOAD", "FAKETIME_TIMESTAMP_FILE", "FAKETIME_NO_CACHE", "FAKETIME_DONT_FAKE_MONOTONIC"})
    ::unsetenv(name);
  std::vector<Process*> set = {sim.get(), driver.get()};
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok({"base_driver"}) && truth.poses.size() > 5; }, 30s))
      << logs_of(set);
  ASSERT_TRUE(drive_until(bus, 0.3, [&] { return truth.speed() > 0.25; })) << logs_of(set);

  // NTP steps the wall clock back an hour.
  write_file(offset_file, "-3600\n");
  const std::int64_t stepped_utime = truth.clock_utime;
  const std::size_t first_after_step = truth.poses.size();
  // Commanded for 1.5 simulated seconds more: the robot drives on all the time.
  ASSERT_TRUE(drive_until(bus, 0.3, [&] { return truth.clock_utime > stepped_utime + 1'500'000; })) << logs_of(set);
  double slowest = 1.0;
  for (std::size_t i = first_after_step; i < truth.poses.size(); ++i)
    if (truth.poses[i].utime - truth.poses[first_after_step].utime > 200'000)
      slowest = std::min(slowest, truth.speed_at(i));
  EXPECT_GT(slowest, 0.2) << "the robot slowed down or stopped while commanded after the wall clock step";
  // ODOMETRY is stamped with the (stepped) wall clock: the step is really there.
  std::optional<pex::odometry_t> odometry;
  bus.on<pex::odometry_t>(std::string(ch::kOdometry), [&](const pex::odometry_t& o) { odometry = o; });
  ASSERT_TRUE(bus.spin_until([&] { return odometry.has_value(); }, 5s));
  const std::int64_t wall_now = std::chrono::duration_cast<std::chrono::microseconds>(
                                    std::chrono::system_clock::now().time_since_epoch())
                                    .count();
  EXPECT_LT(odometry->utime, wall_now - 3'000'000'000LL) << "the driver's wall clock was not stepped";

  // The commands stop: the stale-command timeout (cmd_timeout_ms 250) ramps
  // the wheels to zero as without the step.
  const std::int64_t last_command_utime = truth.clock_utime;
  const std::size_t first_after_commands = truth.poses.size();
  ASSERT_TRUE(bus.spin_until([&] { return truth.clock_utime > last_command_utime + 2'000'000; }, 30s));
  const std::int64_t stop_utime = truth.stood_from(first_after_commands);
  ASSERT_GE(stop_utime, 0) << "the wheels kept turning on a stale command after the wall clock step";
  const double stop_ms = static_cast<double>(stop_utime - last_command_utime) * 1e-3;
  EXPECT_LE(stop_ms, 1000.0) << "stood " << stop_ms << " ms after the last command";
  std::printf("wall clock stepped back 1 h: robot stood %.0f ms (simulated) after the last command\n", stop_ms);
  for (Process* p : set) EXPECT_EQ(p->stop(5s), 0) << p->name() << "\n" << p->output();
  std::filesystem::remove_all(dir);
}
