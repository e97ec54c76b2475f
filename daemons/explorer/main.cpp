// pex-explorer: frontier exploration (paper, Algorithm 1). MAP and a pose in,
// BASE_CMD and EXPLORE_STATE out. All planning is in common/planning; this file
// only wires messages to the ExplorerNode (explorer_node.hpp).
#include <algorithm>
#include <chrono>
#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#include <pex/daemon_status_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>

#include "explorer_node.hpp"
#include "runtime/channels.hpp"
#include "runtime/daemon.hpp"

namespace ch = pex::runtime::channels;
using pex::explorer::ExplorerNode;

namespace {
std::chrono::microseconds period_of(double rate_hz) {
  return std::chrono::microseconds(static_cast<std::int64_t>(1e6 / rate_hz));
}
}  // namespace

int main(int argc, char** argv) {
  return pex::runtime::run_daemon(
      argc, argv, {"explorer", "frontier exploration: goals on frontiers, shortest paths, path following"},
      [](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
        auto explorer = std::make_shared<ExplorerNode>(pex::explorer::load_options(config));
        const auto& options = explorer->options();

        node.subscribe<pex::polygon_map_t>(ch::kMap, [&node, explorer](const pex::polygon_map_t& msg) {
          if (auto why = explorer->on_map(msg, node.now_utime()); !why.empty()) throw pex::runtime::BadInput(why);
        });
        node.subscribe<pex::pose_t>(options.pose_channel, [&node, explorer](const pex::pose_t& msg) {
          if (auto why = explorer->on_pose(msg, node.now_utime()); !why.empty()) throw pex::runtime::BadInput(why);
        });

        // Commands at a fixed rate: the mission's while MOVING, zero otherwise.
        // The log tells each phase change and each new goal.
        auto last_phase = std::make_shared<pex::planning::Phase>(pex::planning::Phase::kIdle);
        auto last_status = std::make_shared<std::string>();
        node.every(period_of(options.cmd_rate_hz), [&node, explorer, last_phase, last_status](std::int64_t now_utime) {
          const auto started = std::chrono::steady_clock::now();
          node.publish(ch::kBaseCmd, explorer->step(now_utime));
          // Planning runs inside the step: its duration is the explorer's latency.
          const auto step_us =
              std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - started).count();
          node.counter("step_us_last") = step_us;
          node.counter("step_us_max") = std::max<std::int64_t>(node.counter("step_us_max"), step_us);
          const auto& out = explorer->last_output();
          if (out.phase != *last_phase || (out.planned && out.status != *last_status)) {
            spdlog::info("{}: {}", pex::planning::to_string(out.phase), out.status);
            *last_phase = out.phase;
            *last_status = out.status;
          }
          if (out.degraded) {
            node.set_state(pex::daemon_status_t::STATE_DEGRADED, out.degraded_reason);
          } else {
            node.set_state(pex::daemon_status_t::STATE_OK);
          }
          const auto& c = explorer->counters();
          node.counter("maps_accepted") = c.maps_accepted;
          node.counter("map_polygons_dropped") = c.map_polygons_dropped;
          node.counter("plans") = c.plans;
          node.counter("goals_reached") = c.goals_reached;
          node.counter("goals_given_up") = c.goals_given_up;
          node.counter("phase") = static_cast<std::int64_t>(out.phase);
        });
        node.every(period_of(options.state_rate_hz), [&node, explorer](std::int64_t now_utime) {
          node.publish(ch::kExploreState, explorer->state_message(now_utime));
        });
        node.on_shutdown([&node] { node.publish(ch::kBaseCmd, ExplorerNode::stop_command(node.now_utime())); });
      });
}
