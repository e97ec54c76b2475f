// The explorer explores a small simulated world on its own: pex-sim (world
// worlds/two_rooms.wkt), pex-lidar-reader, pex-base-driver, pex-polygon-mapper
// (poses from SIM_TRUTH, so no SLAM is involved) and pex-explorer (pose_channel
// SIM_TRUTH) on a real LCM bus in a private network namespace. The mission must
// end DONE with most of the world mapped, without the robot touching a wall.
#include <gtest/gtest.h>

#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <regex>

#include "harness.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;

namespace {

// `text` with top-level `key` set to `value` (a TOML literal): the key's line
// is replaced, or the key is added at the top (before any [section]).
std::string with_key(const std::string& text, const std::string& key, const std::string& value) {
  const std::regex line("^[ \\t]*" + key + "[ \\t]*=.*$", std::regex::multiline);
  if (std::regex_search(text, line)) return std::regex_replace(text, line, key + " = " + value);
  return key + " = " + value + "\n" + text;
}

std::string write_config(const std::string& dir, const std::string& daemon, const std::string& text) {
  const std::string path = dir + "/" + daemon + ".toml";
  write_file(path, text);
  return path;
}

// The world's free area, from the comment in worlds/two_rooms.wkt.
constexpr double kWorldFreeAreaM2 = 82.66;
// The mission's time budget (wall clock; generous: the machine is shared).
constexpr auto kBudget = 420s;

std::int64_t counter_of(const pex::daemon_status_t& s, const std::string& name) {
  for (int i = 0; i < s.ncounters; ++i)
    if (s.counter_names[static_cast<std::size_t>(i)] == name) return s.counter_values[static_cast<std::size_t>(i)];
  return -1;
}

}  // namespace

TEST(Exploration, ExplorerExploresTheTwoRoomsWorldUntilDone) {
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  Bus bus;
  const std::string dir = make_temp_dir("exploration");

  const std::string sim_config = write_config(
      dir, "sim",
      with_key(read_file(sim_config_of("sim")), "world_file", "\"" + source_path("worlds/two_rooms.wkt") + "\""));
  const std::string mapper_config = write_config(
      dir, "polygon_mapper", with_key(read_file(sim_config_of("polygon_mapper")), "pose_source", "\"sim_truth\""));
  const std::string explorer_config = write_config(
      dir, "explorer", with_key(read_file(sim_config_of("explorer")), "pose_channel", "\"SIM_TRUTH\""));

  std::optional<pex::explore_state_t> state;
  std::vector<pex::explore_state_t> states;
  bus.on<pex::explore_state_t>("EXPLORE_STATE", [&](const pex::explore_state_t& s) {
    state = s;
    if (states.empty() || states.back().phase != s.phase) states.push_back(s);
  });
  std::optional<pex::pose_t> truth;
  bus.on<pex::pose_t>("SIM_TRUTH", [&](const pex::pose_t& p) { truth = p; });
  std::optional<pex::polygon_map_t> map;
  bus.on<pex::polygon_map_t>("MAP", [&](const pex::polygon_map_t& m) { map = m; });
  std::optional<pex::velocity_cmd_t> cmd;
  bus.on<pex::velocity_cmd_t>("BASE_CMD", [&](const pex::velocity_cmd_t& c) { cmd = c; });

  std::vector<std::unique_ptr<Process>> set;
  set.push_back(start_daemon("sim", dir, {}, sim_config));
  set.push_back(start_daemon("lidar_reader", dir));
  set.push_back(start_daemon("base_driver", dir));
  set.push_back(start_daemon("polygon_mapper", dir, {}, mapper_config));
  set.push_back(start_daemon("explorer", dir, {}, explorer_config));

  auto finished = [&] {
    return state && (state->phase == pex::explore_state_t::PHASE_DONE ||
                     state->phase == pex::explore_state_t::PHASE_FAILED);
  };
  bus.spin_until(finished, kBudget);
  bus.spin_for(1s);  // the last commands after the end

  std::string report;
  for (const auto& s : states) report += "phase " + std::to_string(s.phase) + ": " + s.status + "\n";
  if (state)
    report += "last: " + state->status + ", explored " + std::to_string(state->explored_area_m2) +
              " m^2, travelled " + std::to_string(state->distance_travelled_m) + " m\n";
  if (auto it = bus.status().find("explorer"); it != bus.status().end())
    report += "goals reached " + std::to_string(counter_of(it->second, "goals_reached")) + ", given up " +
              std::to_string(counter_of(it->second, "goals_given_up")) + ", plans " +
              std::to_string(counter_of(it->second, "plans")) + ", longest step " +
              std::to_string(counter_of(it->second, "step_us_max")) + " us\n";
  if (truth) report += "robot at " + std::to_string(truth->x) + ", " + std::to_string(truth->y) + "\n";
  auto report_with_logs = [&] {
    std::string r = report;
    for (auto& p : set) r += "--- " + p->name() + " (tail)\n" + p->output().substr(p->output().size() > 3000 ? p->output().size() - 3000 : 0);
    return r;
  };

  ASSERT_TRUE(state.has_value()) << report_with_logs();
  EXPECT_EQ(state->phase, +pex::explore_state_t::PHASE_DONE) << report_with_logs();
  ASSERT_TRUE(map.has_value()) << report_with_logs();
  // Most of the world is mapped (the map's free space loses a band along each
  // wall and the corners the laser never saw).
  EXPECT_GT(state->explored_area_m2, 0.8 * kWorldFreeAreaM2) << report;
  EXPECT_LT(state->explored_area_m2, 1.05 * kWorldFreeAreaM2) << report;
  // It had to drive: the right room is not visible from the start.
  EXPECT_GT(state->distance_travelled_m, 3.0) << report;
  // Stopped at the end.
  ASSERT_TRUE(cmd.has_value());
  EXPECT_EQ(cmd->v, 0.0);
  EXPECT_EQ(cmd->omega, 0.0);
  // The robot never touched a wall (the sim counts physics steps in contact).
  auto sim_status = bus.status().find("sim");
  ASSERT_NE(sim_status, bus.status().end());
  // (The counter appears with the first collision: absent means none.)
  EXPECT_LE(counter_of(sim_status->second, "collision_steps"), 0) << report;
  auto explorer_status = bus.status().find("explorer");
  ASSERT_NE(explorer_status, bus.status().end());
  EXPECT_EQ(explorer_status->second.msgs_rejected, 0) << report_with_logs();

  for (auto& p : set) {
    EXPECT_TRUE(p->running()) << p->name() << " exited early:\n" << p->output();
    EXPECT_EQ(p->stop(5s), 0) << p->name();
  }
  std::cout << report;
  if (!HasFailure() && !std::getenv("PEX_KEEP_LOGS")) std::filesystem::remove_all(dir);
}
