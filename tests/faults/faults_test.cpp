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
//   start order: SLAM and the explorer up, the mapper 5 s later (systemd gives
//   no order between them): SLAM republishes its particle set while the robot
//   stands, the late mapper builds its maps from it, the robot sets off.
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
#include <gtest/gtest.h>

#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>

#include "exploration_set.hpp"
#include "harness.hpp"
#include "runtime/channels.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;
namespace ch = pex::runtime::channels;

namespace {

pex::velocity_cmd_t command(double v) { return velocity_command(v, 0.0, "faults_test"); }

// What the bus carries of the truth and the clock.
struct Truth {
  std::vector<pex::pose_t> poses;
  std::int64_t clock_utime = 0;  // newest SIM_CLOCK
  explicit Truth(Bus& bus) {
    bus.on<pex::pose_t>(std::string(ch::kSimTruth), [this](const pex::pose_t& p) { poses.push_back(p); });
    bus.on<pex::sim_clock_t>(std::string(ch::kSimClock), [this](const pex::sim_clock_t& c) { clock_utime = c.utime; });
  }
  // Speed (m/s) over the truth poses of the last `window_us` of simulated time.
  double speed(std::int64_t window_us = 100'000) const {
    if (poses.size() < 2) return 0.0;
    const auto& b = poses.back();
    for (auto it = poses.rbegin(); it != poses.rend(); ++it)
      if (b.utime - it->utime >= window_us)
        return std::hypot(b.x - it->x, b.y - it->y) / (static_cast<double>(b.utime - it->utime) * 1e-6);
    return 0.0;
  }
};

}  // namespace

TEST(Faults, KilledBaseDriverStopsTheWheelsWithin300msAndARestartedOneDrivesAgain) {
  Bus bus;
  Truth truth(bus);
  const std::string dir = make_temp_dir("faults-driver");
  // two_rooms: 4 m of free floor ahead of the start pose.
  const std::string sim_config = dir + "/sim.toml";
  write_file(sim_config, with_key(read_file(sim_config_of("sim")), "world_file",
                                  "\"" + source_path("worlds/two_rooms.wkt") + "\""));
  auto sim = start_daemon("sim", dir, {}, sim_config);
  auto driver = start_daemon("base_driver", dir);
  std::vector<Process*> set = {sim.get(), driver.get()};
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok({"base_driver"}) && truth.poses.size() > 5; }, 30s))
      << logs_of(set);

  // Drive as an explorer would: a command every 50 ms.
  auto drive_until = [&](double v, const std::function<bool()>& done) {
    return bus.spin_until(
        [&] {
          bus.publish(std::string(ch::kBaseCmd), command(v));
          bus.spin_for(50ms);
          return done();
        },
        60s);
  };
  ASSERT_TRUE(drive_until(0.3, [&] { return truth.speed() > 0.25; })) << logs_of(set);

  // kill -9: no zero command, no NMT stop, nothing more from the driver.
  const std::int64_t kill_utime = truth.clock_utime;  // the test's newest clock: at or before the kill
  driver->kill_hard();
  const std::size_t first_after_kill = truth.poses.size();
  // The commands go on (the explorer does not know); 1.5 s of simulated time.
  ASSERT_TRUE(drive_until(0.3, [&] { return truth.clock_utime > kill_utime + 1'500'000; })) << logs_of(set);

  // When did the robot stand? The first truth pose from which it moves less
  // than 2 mm in all the rest (at least 500 ms of it).
  std::int64_t stop_utime = -1;
  for (std::size_t i = first_after_kill; i < truth.poses.size() && stop_utime < 0; ++i) {
    if (truth.poses.back().utime - truth.poses[i].utime < 500'000) break;
    bool stands = true;
    for (std::size_t j = i + 1; j < truth.poses.size() && stands; ++j)
      stands = std::hypot(truth.poses[j].x - truth.poses[i].x, truth.poses[j].y - truth.poses[i].y) < 0.002;
    if (stands) stop_utime = truth.poses[i].utime;
  }
  ASSERT_GE(stop_utime, 0) << "the wheels kept turning after kill -9 of the driver";
  const double stop_ms = static_cast<double>(stop_utime - kill_utime) * 1e-3;
  EXPECT_LE(stop_ms, 300.0) << "stood " << stop_ms << " ms after the kill";
  std::printf("robot stood %.0f ms (simulated) after kill -9 of pex-base-driver\n", stop_ms);

  // A restarted driver configures the drives again and drives.
  driver = start_daemon("base_driver", dir);
  set = {sim.get(), driver.get()};
  EXPECT_TRUE(drive_until(0.3, [&] { return bus.all_ok({"base_driver"}) && truth.speed() > 0.25; }))
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
  // 4 simulated seconds without scans (the mapper's input timeout is 3 s).
  set.spin_sim([] { return false; }, 4.0);
  ASSERT_GT(poses.size(), first_after_kill + 10);
  // Standing: over the last 1.5 s of them the robot moved less than 2 cm.
  const auto& last = poses.back();
  for (std::size_t i = first_after_kill; i < poses.size(); ++i) {
    if (last.utime - poses[i].utime > 1'500'000) continue;
    EXPECT_LT(std::hypot(last.x - poses[i].x, last.y - poses[i].y), 0.02)
        << "the robot drove on without scans (" << set.sim_seconds() - kill_s << " s after the kill)";
  }
  // Health tells the truth: the explorer and the mapper cannot do their job.
  set.bus().spin_for(1200ms);  // a heartbeat after the timeouts
  EXPECT_EQ(set.bus().status().at("explorer").state, +pex::daemon_status_t::STATE_DEGRADED);
  EXPECT_EQ(set.bus().status().at("polygon_mapper").state, +pex::daemon_status_t::STATE_DEGRADED);
  ASSERT_TRUE(set.state());
  EXPECT_NE(set.state()->status.find("no laser scan"), std::string::npos) << set.state()->status;

  // The reader back (systemd restarts it): the mission goes on to its end.
  set.restart("lidar_reader");
  ASSERT_TRUE(set.spin_to_end()) << set.report_with_logs();
  EXPECT_EQ(set.phase(), +pex::explore_state_t::PHASE_DONE) << set.report_with_logs();
  // two_rooms: 82.66 m2 free; the map loses a band along each wall.
  EXPECT_GT(set.state()->explored_area_m2, 0.8 * 82.66) << set.report();
  EXPECT_EQ(set.clock()->collisions, 0);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
}

TEST(Faults, RestartedBaseDriverResetsOdometryAndSlamDoesNotJump) {
  Bus bus;
  Truth truth(bus);
  std::vector<pex::pose_t> slam_poses;
  bus.on<pex::pose_t>(std::string(ch::kSlamPose), [&](const pex::pose_t& p) { slam_poses.push_back(p); });
  const std::string dir = make_temp_dir("faults-odometry");
  const std::string sim_config = dir + "/sim.toml";
  write_file(sim_config, with_key(read_file(sim_config_of("sim")), "world_file",
                                  "\"" + source_path("worlds/two_rooms.wkt") + "\""));
  auto sim = start_daemon("sim", dir, {}, sim_config);
  auto reader = start_daemon("lidar_reader", dir);
  auto driver = start_daemon("base_driver", dir);
  auto slam = start_daemon("slam", dir);
  std::vector<Process*> set = {sim.get(), reader.get(), driver.get(), slam.get()};
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok({"base_driver", "slam"}) && !slam_poses.empty(); }, 30s))
      << logs_of(set);
  const pex::pose_t truth_start = truth.poses.back();
  const pex::pose_t slam_start = slam_poses.back();
  auto drive_until = [&](const std::function<bool()>& done) {
    return bus.spin_until(
        [&] {
          bus.publish(std::string(ch::kBaseCmd), command(0.3));
          bus.spin_for(50ms);
          return done();
        },
        60s);
  };
  auto travelled = [&] { return std::hypot(truth.poses.back().x - truth_start.x, truth.poses.back().y - truth_start.y); };
  ASSERT_TRUE(drive_until([&] { return travelled() > 1.0; })) << logs_of(set);

  driver->kill_hard();
  bus.spin_until([&] { return truth.speed() < 0.01; }, 10s);  // the drives stop on their own
  driver = start_daemon("base_driver", dir);
  set = {sim.get(), reader.get(), driver.get(), slam.get()};
  ASSERT_TRUE(drive_until([&] { return bus.all_ok({"base_driver"}) && travelled() > 2.0; })) << logs_of(set);
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

TEST(Faults, MapperStartedLastStillGetsItsMapsAndTheRobotSetsOff) {
  Bus bus;
  Truth truth(bus);
  std::optional<pex::explore_state_t> state;
  bus.on<pex::explore_state_t>(std::string(ch::kExploreState), [&](const pex::explore_state_t& s) { state = s; });
  const std::string dir = make_temp_dir("faults-order");
  const std::string sim_config = dir + "/sim.toml";
  write_file(sim_config, with_key(read_file(sim_config_of("sim")), "world_file",
                                  "\"" + source_path("worlds/two_rooms.wkt") + "\""));
  std::vector<std::unique_ptr<Process>> set;
  set.push_back(start_daemon("sim", dir, {}, sim_config));
  for (const char* name : {"lidar_reader", "base_driver", "slam", "explorer"}) set.push_back(start_daemon(name, dir));
  auto all = [&] {
    std::vector<Process*> p;
    for (auto& q : set) p.push_back(q.get());
    return p;
  };
  // 5 simulated seconds without a mapper: no map, the robot waits.
  ASSERT_TRUE(bus.spin_until([&] { return truth.clock_utime > 0 && !truth.poses.empty(); }, 30s)) << logs_of(all());
  const std::int64_t start = truth.clock_utime;
  ASSERT_TRUE(bus.spin_until([&] { return truth.clock_utime > start + 5'000'000; }, 60s)) << logs_of(all());
  ASSERT_TRUE(state);
  EXPECT_EQ(state->phase, +pex::explore_state_t::PHASE_IDLE) << state->status;
  const pex::pose_t before = truth.poses.back();

  set.push_back(start_daemon("polygon_mapper", dir));
  const std::int64_t mapper_started = truth.clock_utime;
  const bool set_off = bus.spin_until(
      [&] {
        const auto& p = truth.poses.back();
        return std::hypot(p.x - before.x, p.y - before.y) > 0.3 || truth.clock_utime > mapper_started + 20'000'000;
      },
      120s);
  ASSERT_TRUE(set_off);
  const auto& p = truth.poses.back();
  EXPECT_GT(std::hypot(p.x - before.x, p.y - before.y), 0.3)
      << "the robot never set off after the mapper started last: " << (state ? state->status : "no state") << "\n"
      << logs_of(all());
  for (auto& q : set) EXPECT_EQ(q->stop(5s), 0) << q->name() << "\n" << q->output();
  std::filesystem::remove_all(dir);
}

TEST(Faults, KilledExplorerTakesItsMissionUpFromTheCheckpoint) {
  const std::string checkpoint = make_temp_dir("faults-explorer-state") + "/mission.txt";
  ExplorationSet set("faults-explorer",
                     {.explorer_keys = {{"checkpoint_file", "\"" + checkpoint + "\""}, {"checkpoint_period_s", "0.5"}}});
  // Two goals reached, and a checkpoint written after the second.
  ASSERT_TRUE(set.spin_sim([&] { return set.state() && set.state()->goals_reached >= 2; }, 300.0))
      << set.report_with_logs();
  set.spin_sim([] { return false; }, 1.0);
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
  ASSERT_TRUE(set.spin_to_end()) << set.report_with_logs();
  EXPECT_EQ(set.phase(), +pex::explore_state_t::PHASE_DONE) << set.report_with_logs();
  EXPECT_GT(set.state()->explored_area_m2, 0.8 * 82.66) << set.report();
  EXPECT_GT(set.bus().status().at("explorer").ncounters, 0);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
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
  ASSERT_TRUE(set.spin_to_end()) << set.report_with_logs();
  EXPECT_EQ(set.phase(), +pex::explore_state_t::PHASE_DONE) << set.report_with_logs();
  // The whole world mapped (82.66 m^2 free), nothing beyond it (ghost space).
  EXPECT_GT(set.state()->explored_area_m2, 0.9 * 82.66) << set.report();
  EXPECT_LT(maps.back().free_area_m2, 1.03 * 82.66) << set.report();
  const auto& status = set.bus().status().at("polygon_mapper");
  EXPECT_GE(counter_of(status, "slam_resyncs"), 1) << "the restarted mapper followed parents it never saw";
  EXPECT_EQ(counter_of(status, "slam_epoch_changes"), 0);
  set.stop_all();
  set.clean_up(::testing::Test::HasFailure());
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(std::filesystem::path(checkpoint).parent_path());
}
