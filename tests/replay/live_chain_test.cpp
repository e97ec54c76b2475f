// Real data through the live daemon set: the head of the Intel log, converted
// by pex-carmen2lcm, is played by lcm-logplayer into pex-slam and
// pex-polygon-mapper (pose_source = "slam", one map per particle) on a real LCM
// bus in a private network namespace. The mapper must apply every SLAM_UPDATE
// the filter published, publish the best particle's map, and the filter must
// make the same updates as its offline run of the same log.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <pex/polygon_map_t.hpp>
#include <pex/slam_update_t.hpp>

#include "exploration_set.hpp"
#include "harness.hpp"
#include "runtime/channels.hpp"

namespace fs = std::filesystem;
using namespace pex::testing;
using namespace std::chrono_literals;
namespace ch = pex::runtime::channels;

namespace {

constexpr int kScans = 500;  // about the first 100 s of the log


}  // namespace

TEST(LiveChain, IntelHeadThroughLogplayerSlamAndPerParticleMapper) {
  const fs::path clf = shared_path("data/intel.clf");
  if (!fs::exists(clf)) GTEST_SKIP() << "no Intel log at " << clf;
  const std::string dir = make_temp_dir("livechain");
  {
    std::ifstream in(clf);
    std::ofstream out(dir + "/head.clf");
    std::string line;
    for (int scans = 0; scans < kScans && std::getline(in, line);) {
      out << line << '\n';
      if (line.rfind("FLASER ", 0) == 0) ++scans;
    }
  }
  const std::string head = dir + "/head.lcm";
  ASSERT_EQ(run_to_completion({bin_path("pex-carmen2lcm"), dir + "/head.clf", head}).exit_code, 0);

  // Offline reference: the same handlers fed from the log, with the motion
  // model the robot's overlay below has too (the logs' robots': GMapping's).
  const auto offline = run_to_completion({bin_path("pex-slam"), "--config", source_path("config/slam.toml"), "--config",
                                          source_path("config/datasets/slam.toml"), "--log", head, "--out",
                                          dir + "/offline.lcm", "--log-level", "warn"},
                                         120s);
  ASSERT_EQ(offline.exit_code, 0) << offline.output;
  int offline_updates = 0;
  {
    lcm::LogFile log(dir + "/offline.lcm", "r");
    while (const lcm::LogEvent* ev = log.readNextEvent())
      if (ev->channel == ch::kSlamUpdate) ++offline_updates;
  }
  ASSERT_GT(offline_updates, 5);

  Bus bus;
  int live_updates = 0;
  int64_t last_generation = -1;
  bus.on<pex::slam_update_t>(std::string(ch::kSlamUpdate), [&](const pex::slam_update_t& u) {
    ++live_updates;
    last_generation = u.generation;
  });
  pex::polygon_map_t last_map{};
  int maps = 0;
  bus.on<pex::polygon_map_t>(std::string(ch::kMap), [&](const pex::polygon_map_t& m) {
    ++maps;
    last_map = m;
  });
  // Real data, no simulator: the robot's configs, as its units read them: config/X.toml,
  // then the robot's overlay (clock = "system"; they name no device), with the
  // checkpoints in the test's folder: a robot's /var/lib/polyexplore, where one
  // exists, is neither read nor written.
  auto robot_overlay = [&](const std::string& daemon) {
    return write_config(dir, daemon + "-robot",
                        with_key(read_file(source_path("config/robot/" + daemon + ".toml")), "checkpoint_file",
                                 "\"" + dir + "/" + daemon + "-checkpoint.bin\""));
  };
  auto slam = start_daemon("slam", dir, {"--config", robot_overlay("slam")});
  auto mapper = start_daemon("polygon_mapper", dir, {"--config", robot_overlay("polygon_mapper")});
  ASSERT_TRUE(bus.spin_until([&] { return bus.all_ok({"slam", "polygon_mapper"}); }, 5s));

  Process player({"/usr/bin/lcm-logplayer", "--speed=5", std::string("--lcm-url=") + kTestLcmUrl, head},
                 dir + "/player.log");
  ASSERT_TRUE(bus.spin_until([&] { return !player.running(); }, 120s)) << "lcm-logplayer did not finish";
  EXPECT_EQ(player.wait(1s), 0) << player.output();
  // The mapper catches up: its newest MAP is of the filter's newest generation.
  const bool caught_up =
      bus.spin_until([&] { return maps > 0 && last_map.generation == last_generation; }, 60s);
  EXPECT_TRUE(caught_up) << "MAP generation " << last_map.generation << ", SLAM generation " << last_generation
                         << "\n" << mapper->output();

  EXPECT_EQ(live_updates, offline_updates) << "live and offline filters made different updates";
  EXPECT_GE(last_map.particle, 0);
  EXPECT_GT(last_map.free_area_m2, 50.0);
  EXPECT_GT(last_map.obstacle_length_m, 20.0);

  bus.spin_for(1200ms);  // a fresh heartbeat with final counters
  const auto& status = bus.status();
  ASSERT_TRUE(status.count("polygon_mapper"));
  const auto& ms = status.at("polygon_mapper");
  EXPECT_EQ(counter_of(ms, "slam_updates"), live_updates);
  EXPECT_EQ(counter_of(ms, "updates_without_scan"), 0);
  EXPECT_EQ(ms.msgs_rejected, 0);
  EXPECT_EQ(status.at("slam").msgs_rejected, 0);

  EXPECT_EQ(slam->stop(), 0) << slam->output();
  EXPECT_EQ(mapper->stop(), 0) << mapper->output();
  fs::remove_all(dir);
}
