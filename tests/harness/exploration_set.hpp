#pragma once
// The exploration set as the tests start it (see ExplorationSet).
#include <gtest/gtest.h>

#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <optional>
#include <regex>
#include <string>
#include <vector>

#include "harness.hpp"

namespace pex::testing {

using namespace std::chrono_literals;

// Wall-clock budget of a wait on the set: only there so that a hung set fails
// instead of hanging the suite; every wait ends on a state long before it.
inline constexpr auto kSetBudget = std::chrono::seconds(600);

// `text` with top-level `key` set to `value` (a TOML literal): the key's line
// is replaced, or the key is added at the top (before any [section]).
inline std::string with_key(const std::string& text, const std::string& key, const std::string& value) {
  const std::regex line("^[ \\t]*" + key + "[ \\t]*=.*$", std::regex::multiline);
  if (std::regex_search(text, line)) return std::regex_replace(text, line, key + " = " + value);
  return key + " = " + value + "\n" + text;
}

inline std::string write_config(const std::string& dir, const std::string& daemon, const std::string& text) {
  const std::string path = dir + "/" + daemon + ".toml";
  write_file(path, text);
  return path;
}

// The mission has ended on its own (DONE, DONE_WITH_UNREACHABLE or FAILED).
inline bool mission_finished(std::int8_t phase) {
  return phase == pex::explore_state_t::PHASE_DONE || phase == pex::explore_state_t::PHASE_DONE_WITH_UNREACHABLE ||
         phase == pex::explore_state_t::PHASE_FAILED;
}

using ConfigKeys = std::vector<std::pair<std::string, std::string>>;  // (top-level key, TOML literal)

struct SetOptions {
  double speed = 1.0;  // the simulator's speed factor
  bool autostart = true;
  std::string world = "two_rooms";
  // false: the mapper on SIM_TRUTH and the explorer on SIM_TRUTH, no SLAM.
  // true: pex-slam in the set, the mapper on SLAM_UPDATE (a map per particle)
  // and the explorer on SLAM_POSE, as on the robot.
  bool slam = false;
  // (Braced: designated initializers may then leave them out without a warning.)
  ConfigKeys explorer_keys{}, mapper_keys{}, slam_keys{}, sim_keys{};
  // Daemons of the set not started with it ("sim", "slam", ...): start() starts them.
  std::vector<std::string> held_back{};
};

// The exploration set on a world: pex-sim, pex-lidar-reader, pex-base-driver,
// (pex-slam,) pex-polygon-mapper and pex-explorer, each on the simulator's
// clock, with what the test bus heard. For the exploration and the fault tests.
class ExplorationSet {
 public:
  ExplorationSet(const std::string& tag, const SetOptions& options) : dir_(make_temp_dir(tag)), options_(options) {
    std::string sim = with_key(read_file(sim_config_of("sim")), "world_file",
                               "\"" + source_path("worlds/" + options.world + ".wkt") + "\"");
    sim = with_key(sim, "speed_factor", std::to_string(options.speed));
    for (const auto& [key, value] : options.sim_keys) sim = with_key(sim, key, value);
    std::string mapper = with_key(read_file(sim_config_of("polygon_mapper")), "pose_source",
                                  options.slam ? "\"slam\"" : "\"sim_truth\"");
    for (const auto& [key, value] : options.mapper_keys) mapper = with_key(mapper, key, value);
    std::string explorer = with_key(read_file(sim_config_of("explorer")), "pose_channel",
                                    options.slam ? "\"SLAM_POSE\"" : "\"SIM_TRUTH\"");
    explorer = with_key(explorer, "autostart", options.autostart ? "true" : "false");
    for (const auto& [key, value] : options.explorer_keys) explorer = with_key(explorer, key, value);
    std::string slam = read_file(sim_config_of("slam"));
    for (const auto& [key, value] : options.slam_keys) slam = with_key(slam, key, value);

    bus_.on<pex::explore_state_t>("EXPLORE_STATE", [this](const pex::explore_state_t& s) {
      if (states_.empty() || states_.back().phase != s.phase) states_.push_back(s);
      state_ = s;
    });
    bus_.on<pex::pose_t>("SIM_TRUTH", [this](const pex::pose_t& p) {
      if (!first_truth_) first_truth_ = p;
      truth_ = p;
    });
    bus_.on<pex::sim_clock_t>("SIM_CLOCK", [this](const pex::sim_clock_t& c) {
      // Where each contact began, for the report: a collision in a run on a
      // loaded machine is seldom seen again.
      if (c.collisions > (clock_ ? clock_->collisions : 0) && contacts_.size() < kContactsReported) {
        std::string where = "contact " + std::to_string(c.collisions) + " at sim " +
                            std::to_string(static_cast<double>(c.sim_time_us) * 1e-6) + " s";
        if (truth_)
          where += ": robot at " + std::to_string(truth_->x) + ", " + std::to_string(truth_->y) + ", heading " +
                   std::to_string(truth_->theta) + " rad";
        if (cmd_) where += "; last command v " + std::to_string(cmd_->v) + " m/s, omega " + std::to_string(cmd_->omega) + " rad/s";
        contacts_.push_back(where);
      }
      clock_ = c;
    });
    bus_.on<pex::velocity_cmd_t>("BASE_CMD", [this](const pex::velocity_cmd_t& c) { cmd_ = c; });
    bus_.on<pex::polygon_map_t>("MAP", [this](const pex::polygon_map_t& m) { map_ = m; });

    write_config(dir_, "sim", sim);
    if (options.slam) write_config(dir_, "slam", slam);
    write_config(dir_, "polygon_mapper", mapper);
    write_config(dir_, "explorer", explorer);
    for (const char* name : {"sim", "lidar_reader", "base_driver", "slam", "polygon_mapper", "explorer"}) {
      if (std::string(name) == "slam" && !options.slam) continue;
      set_.push_back({name, nullptr});
      if (std::find(options.held_back.begin(), options.held_back.end(), name) == options.held_back.end())
        start(name);
    }
  }

  Bus& bus() { return bus_; }
  const std::string& dir() const { return dir_; }
  // One daemon of the set ("lidar_reader", ...); nullptr if it is not one or not started.
  Process* process(const std::string& name) {
    for (auto& [n, p] : set_)
      if (n == name) return p.get();
    return nullptr;
  }
  // Starts a daemon of the set (held back, or again after a kill) with its config.
  void start(const std::string& name) {
    for (auto& [n, p] : set_)
      if (n == name) {
        const std::string config = dir_ + "/" + name + ".toml";
        p = start_daemon(name, dir_, {}, std::filesystem::exists(config) ? config : "");
        return;
      }
    ADD_FAILURE() << name << " is not a daemon of this set";
  }
  void restart(const std::string& name) { start(name); }
  const std::optional<pex::explore_state_t>& state() const { return state_; }
  const std::optional<pex::pose_t>& truth() const { return truth_; }
  const std::optional<pex::pose_t>& first_truth() const { return first_truth_; }
  const std::optional<pex::sim_clock_t>& clock() const { return clock_; }
  const std::optional<pex::velocity_cmd_t>& cmd() const { return cmd_; }
  const std::optional<pex::polygon_map_t>& map() const { return map_; }  // the newest MAP
  const SetOptions& options() const { return options_; }
  std::int8_t phase() const { return state_ ? state_->phase : std::int8_t{-1}; }
  double sim_seconds() const { return clock_ ? static_cast<double>(clock_->sim_time_us) * 1e-6 : 0.0; }

  // Spins until `done` or the simulated clock has run `sim_s` more seconds.
  bool spin_sim(const std::function<bool()>& done, double sim_s) {
    const double until = sim_seconds() + sim_s;
    return bus_.spin_until([&] { return done() || sim_seconds() >= until; }, kSetBudget) && done();
  }

  // Spins until the mission has ended on its own, at most `sim_s` simulated seconds.
  bool spin_to_end(double sim_s = 600.0) {
    return spin_sim([&] { return mission_finished(phase()); }, sim_s);
  }

  // pex-mission COMMAND on the test bus; its exit code.
  int command(const std::string& name) {
    return run_to_completion({bin_path("pex-mission"), name, "--lcm-url", kTestLcmUrl, "--timeout", "20"}, 30s)
        .exit_code;
  }

  std::string report() const {
    std::string r;
    for (const auto& s : states_) r += "phase " + std::to_string(s.phase) + ": " + s.status + "\n";
    if (state_)
      r += "last: " + state_->status + ", explored " + std::to_string(state_->explored_area_m2) +
           " m^2, travelled " + std::to_string(state_->distance_travelled_m) + " m, mission time " +
           std::to_string(state_->mission_time_s) + " s\n";
    if (clock_)
      r += "sim time " + std::to_string(sim_seconds()) + " s, collisions " + std::to_string(clock_->collisions) +
           ", collision steps " + std::to_string(clock_->collision_steps) + "\n";
    for (const auto& where : contacts_) r += where + "\n";
    if (truth_) r += "robot at " + std::to_string(truth_->x) + ", " + std::to_string(truth_->y) + "\n";
    return r;
  }
  std::string report_with_logs() const {
    std::string r = report();
    for (const auto& [name, p] : set_) {
      if (!p) continue;
      const std::string out = p->output();
      r += "--- " + p->name() + " (tail)\n" + out.substr(out.size() > 3000 ? out.size() - 3000 : 0);
    }
    return r;
  }

  // Stops the set; every daemon must have run to the end and stop cleanly.
  void stop_all() {
    for (auto& [name, p] : set_) {
      if (!p) continue;
      EXPECT_TRUE(p->running()) << p->name() << " exited early:\n" << p->output();
      EXPECT_EQ(p->stop(5s), 0) << p->name();
    }
  }
  void clean_up(bool failed) {
    if (!keep_test_dir(failed)) std::filesystem::remove_all(dir_);
  }

 private:
  std::string dir_;
  SetOptions options_;
  Bus bus_;
  std::vector<std::pair<std::string, std::unique_ptr<Process>>> set_;  // (daemon, process or null)
  std::optional<pex::explore_state_t> state_;
  std::vector<pex::explore_state_t> states_;
  std::optional<pex::pose_t> truth_, first_truth_;
  std::optional<pex::sim_clock_t> clock_;
  std::optional<pex::velocity_cmd_t> cmd_;
  std::optional<pex::polygon_map_t> map_;
  static constexpr std::size_t kContactsReported = 5;
  std::vector<std::string> contacts_;  // where the first contacts began
};


}  // namespace pex::testing
