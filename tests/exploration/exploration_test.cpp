// The explorer explores a small simulated world on its own: pex-sim (world
// worlds/two_rooms.wkt), pex-lidar-reader, pex-base-driver, pex-polygon-mapper
// (poses from SIM_TRUTH, so no SLAM is involved) and pex-explorer (pose_channel
// SIM_TRUTH) on a real LCM bus in a private network namespace, every daemon on
// the simulator's clock (clock = "sim"). Each test waits for states
// (EXPLORE_STATE phases, SIM_CLOCK time), never for a fixed wall time.
//
//   - the mission at 10x speed ends DONE with the world mapped, no collision;
//   - the same mission at 1x and at 10x explores the same area (within a few
//     percent) without a collision: the speed changes only the wall time;
//   - with autostart off the robot waits for `pex-mission start`; pause stops
//     it, resume goes on, home brings it back to the start pose.
#include <gtest/gtest.h>

#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include <cmath>
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
// Wall-clock budgets: only there so that a hung set fails instead of hanging
// the suite; every wait ends on a state long before them.
constexpr auto kBudget = 600s;

bool finished(std::int8_t phase) {
  return phase == pex::explore_state_t::PHASE_DONE || phase == pex::explore_state_t::PHASE_DONE_WITH_UNREACHABLE ||
         phase == pex::explore_state_t::PHASE_FAILED;
}

// The set on two_rooms, with what the test bus heard.
class Mission {
 public:
  Mission(const std::string& tag, double speed, bool autostart) : dir_(make_temp_dir(tag)) {
    std::string sim = with_key(read_file(sim_config_of("sim")), "world_file",
                               "\"" + source_path("worlds/two_rooms.wkt") + "\"");
    sim = with_key(sim, "speed_factor", std::to_string(speed));
    const std::string mapper = with_key(read_file(sim_config_of("polygon_mapper")), "pose_source", "\"sim_truth\"");
    std::string explorer = with_key(read_file(sim_config_of("explorer")), "pose_channel", "\"SIM_TRUTH\"");
    explorer = with_key(explorer, "autostart", autostart ? "true" : "false");

    bus_.on<pex::explore_state_t>("EXPLORE_STATE", [this](const pex::explore_state_t& s) {
      if (states_.empty() || states_.back().phase != s.phase) states_.push_back(s);
      state_ = s;
    });
    bus_.on<pex::pose_t>("SIM_TRUTH", [this](const pex::pose_t& p) {
      if (!first_truth_) first_truth_ = p;
      truth_ = p;
    });
    bus_.on<pex::sim_clock_t>("SIM_CLOCK", [this](const pex::sim_clock_t& c) { clock_ = c; });
    bus_.on<pex::velocity_cmd_t>("BASE_CMD", [this](const pex::velocity_cmd_t& c) { cmd_ = c; });

    set_.push_back(start_daemon("sim", dir_, {}, write_config(dir_, "sim", sim)));
    set_.push_back(start_daemon("lidar_reader", dir_));
    set_.push_back(start_daemon("base_driver", dir_));
    set_.push_back(start_daemon("polygon_mapper", dir_, {}, write_config(dir_, "polygon_mapper", mapper)));
    set_.push_back(start_daemon("explorer", dir_, {}, write_config(dir_, "explorer", explorer)));
  }

  Bus& bus() { return bus_; }
  const std::optional<pex::explore_state_t>& state() const { return state_; }
  const std::optional<pex::pose_t>& truth() const { return truth_; }
  const std::optional<pex::pose_t>& first_truth() const { return first_truth_; }
  const std::optional<pex::sim_clock_t>& clock() const { return clock_; }
  const std::optional<pex::velocity_cmd_t>& cmd() const { return cmd_; }
  std::int8_t phase() const { return state_ ? state_->phase : std::int8_t{-1}; }
  double sim_seconds() const { return clock_ ? static_cast<double>(clock_->sim_time_us) * 1e-6 : 0.0; }

  // Spins until `done` or the simulated clock has run `sim_s` more seconds.
  bool spin_sim(const std::function<bool()>& done, double sim_s) {
    const double until = sim_seconds() + sim_s;
    return bus_.spin_until([&] { return done() || sim_seconds() >= until; }, kBudget) && done();
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
    if (truth_) r += "robot at " + std::to_string(truth_->x) + ", " + std::to_string(truth_->y) + "\n";
    return r;
  }
  std::string report_with_logs() const {
    std::string r = report();
    for (const auto& p : set_) {
      const std::string out = p->output();
      r += "--- " + p->name() + " (tail)\n" + out.substr(out.size() > 3000 ? out.size() - 3000 : 0);
    }
    return r;
  }

  // Stops the set; every daemon must have run to the end and stop cleanly.
  void stop_all() {
    for (auto& p : set_) {
      EXPECT_TRUE(p->running()) << p->name() << " exited early:\n" << p->output();
      EXPECT_EQ(p->stop(5s), 0) << p->name();
    }
  }
  void clean_up(bool failed) {
    if (!failed && !std::getenv("PEX_KEEP_LOGS")) std::filesystem::remove_all(dir_);
  }

 private:
  std::string dir_;
  Bus bus_;
  std::vector<std::unique_ptr<Process>> set_;
  std::optional<pex::explore_state_t> state_;
  std::vector<pex::explore_state_t> states_;
  std::optional<pex::pose_t> truth_, first_truth_;
  std::optional<pex::sim_clock_t> clock_;
  std::optional<pex::velocity_cmd_t> cmd_;
};

struct Outcome {
  std::int8_t phase = -1;
  double explored_m2 = 0.0;
  double travelled_m = 0.0;
  std::int64_t collisions = -1;
};

// A whole mission on two_rooms at `speed`, to its end (at most 600 simulated s).
Outcome explore_two_rooms(double speed, const std::string& tag) {
  Mission m(tag, speed, /*autostart=*/true);
  m.spin_sim([&] { return finished(m.phase()); }, 600.0);
  m.bus().spin_for(500ms);  // the last commands after the end
  Outcome o;
  EXPECT_TRUE(m.state().has_value()) << m.report_with_logs();
  if (!m.state()) return o;
  o.phase = m.state()->phase;
  o.explored_m2 = m.state()->explored_area_m2;
  o.travelled_m = m.state()->distance_travelled_m;
  o.collisions = m.clock() ? m.clock()->collisions : -1;
  EXPECT_EQ(o.phase, +pex::explore_state_t::PHASE_DONE) << m.report_with_logs();
  // Most of the world is mapped (the map's free space loses a band along each
  // wall and the corners the laser never saw).
  EXPECT_GT(o.explored_m2, 0.8 * kWorldFreeAreaM2) << m.report();
  EXPECT_LT(o.explored_m2, 1.05 * kWorldFreeAreaM2) << m.report();
  // It had to drive: the right room is not visible from the start.
  EXPECT_GT(o.travelled_m, 3.0) << m.report();
  // Stopped at the end.
  EXPECT_TRUE(m.cmd() && m.cmd()->v == 0.0 && m.cmd()->omega == 0.0) << m.report();
  // The robot never touched a wall.
  EXPECT_EQ(o.collisions, 0) << m.report();
  auto explorer_status = m.bus().status().find("explorer");
  EXPECT_TRUE(explorer_status != m.bus().status().end() && explorer_status->second.msgs_rejected == 0)
      << m.report_with_logs();
  m.stop_all();
  std::cout << "speed x" << speed << ": " << m.report();
  m.clean_up(::testing::Test::HasFailure());
  return o;
}

}  // namespace

TEST(Exploration, ExploresTheTwoRoomsWorldAtTenTimesSpeed) {
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  const Outcome fast = explore_two_rooms(10.0, "explore-x10");
  EXPECT_EQ(fast.phase, +pex::explore_state_t::PHASE_DONE);
}

TEST(Exploration, SpeedChangesOnlyTheWallTimeNotTheOutcome) {
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  const Outcome slow = explore_two_rooms(1.0, "explore-x1");
  const Outcome fast = explore_two_rooms(10.0, "explore-x10b");
  ASSERT_EQ(slow.phase, +pex::explore_state_t::PHASE_DONE);
  ASSERT_EQ(fast.phase, +pex::explore_state_t::PHASE_DONE);
  // The same coverage within a few percent, and no collision in either run.
  EXPECT_NEAR(fast.explored_m2 / slow.explored_m2, 1.0, 0.04)
      << "x1: " << slow.explored_m2 << " m^2, x10: " << fast.explored_m2 << " m^2";
  EXPECT_EQ(slow.collisions, 0);
  EXPECT_EQ(fast.collisions, 0);
}

TEST(Exploration, MissionCommandsStartPauseResumeAndHome) {
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  Mission m("explore-commands", 5.0, /*autostart=*/false);

  // Booted without autostart: it waits, wheels still, for 10 simulated seconds.
  ASSERT_TRUE(m.spin_sim([&] { return m.phase() == pex::explore_state_t::PHASE_WAITING_START && m.truth(); }, 60.0))
      << m.report_with_logs();
  m.spin_sim([] { return false; }, 10.0);
  ASSERT_TRUE(m.first_truth() && m.truth());
  EXPECT_LT(std::hypot(m.truth()->x - m.first_truth()->x, m.truth()->y - m.first_truth()->y), 0.01) << m.report();
  EXPECT_EQ(m.phase(), +pex::explore_state_t::PHASE_WAITING_START);

  // start: it moves off.
  ASSERT_EQ(m.command("start"), 0) << m.report_with_logs();
  const pex::pose_t start = *m.first_truth();
  ASSERT_TRUE(m.spin_sim(
      [&] { return m.truth() && std::hypot(m.truth()->x - start.x, m.truth()->y - start.y) > 1.0; }, 120.0))
      << m.report_with_logs();

  // pause: the wheels stop and stay stopped while paused.
  ASSERT_EQ(m.command("pause"), 0) << m.report_with_logs();
  m.spin_sim([] { return false; }, 2.0);  // let the base come to rest
  const pex::pose_t paused_at = *m.truth();
  m.spin_sim([] { return false; }, 10.0);
  EXPECT_EQ(m.phase(), +pex::explore_state_t::PHASE_PAUSED);
  EXPECT_LT(std::hypot(m.truth()->x - paused_at.x, m.truth()->y - paused_at.y), 0.02) << m.report();
  ASSERT_TRUE(m.cmd());
  EXPECT_EQ(m.cmd()->v, 0.0);
  EXPECT_EQ(m.cmd()->omega, 0.0);

  // resume: it moves again.
  ASSERT_EQ(m.command("resume"), 0) << m.report_with_logs();
  EXPECT_TRUE(m.spin_sim(
      [&] { return std::hypot(m.truth()->x - paused_at.x, m.truth()->y - paused_at.y) > 0.5 || finished(m.phase()); },
      120.0))
      << m.report_with_logs();

  // home: back to the start pose, then stopped there.
  ASSERT_EQ(m.command("home"), 0) << m.report_with_logs();
  ASSERT_TRUE(m.spin_sim([&] { return m.phase() == pex::explore_state_t::PHASE_HOME; }, 300.0))
      << m.report_with_logs();
  EXPECT_LT(std::hypot(m.truth()->x - start.x, m.truth()->y - start.y), 0.5) << m.report();
  const pex::pose_t home_at = *m.truth();
  m.spin_sim([] { return false; }, 5.0);
  EXPECT_LT(std::hypot(m.truth()->x - home_at.x, m.truth()->y - home_at.y), 0.02) << m.report();
  EXPECT_EQ(m.clock()->collisions, 0) << m.report();
  m.stop_all();
  std::cout << m.report();
  m.clean_up(HasFailure());
}
