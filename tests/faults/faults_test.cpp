// Fault injection on the real daemons (ctest label `faults`): each case kills
// or breaks one part of a running set on a real LCM bus in a private network
// namespace, and checks the expectation against the simulator's truth
// (SIM_TRUTH), on the simulated clock (SIM_CLOCK).
//
//   kill -9 pex-base-driver while driving: the drives notice its heartbeat is
//   gone (CiA 301 consumer heartbeat 0x1016, set up by the driver at
//   bring-up) and quick-stop (0x6007): the robot stands within 300 ms of
//   simulated time. A restarted driver re-arms the watchdog and drives again.
#include <gtest/gtest.h>

#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <regex>

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
  write_file(sim_config, std::regex_replace(read_file(sim_config_of("sim")), std::regex("^world_file *=.*$", std::regex::multiline),
                                            "world_file = \"" + source_path("worlds/two_rooms.wkt") + "\""));
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
