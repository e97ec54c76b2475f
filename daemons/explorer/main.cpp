// pex-explorer: frontier exploration (paper, Algorithm 1). MAP, a pose and
// MISSION_CMD in; BASE_CMD and EXPLORE_STATE out. All planning is in
// common/planning; this file only wires messages to the ExplorerNode
// (explorer_node.hpp), whose plans run on a worker thread.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#include <pex/daemon_status_t.hpp>
#include <pex/mission_cmd_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>

#include "explorer_node.hpp"
#include "map_message.hpp"
#include "runtime/channels.hpp"
#include "runtime/daemon.hpp"
#include "runtime/checkpoint.hpp"

namespace ch = pex::runtime::channels;
using pex::explorer::ExplorerNode;

namespace {
std::chrono::microseconds period_of(double rate_hz) {
  return std::chrono::microseconds(static_cast<std::int64_t>(1e6 / rate_hz));
}
}  // namespace

int main(int argc, char** argv) {
  return pex::runtime::run_daemon(
      argc, argv, {.name = "explorer",
       .description = "frontier exploration: goals on frontiers, shortest paths, path following",
       .load_options = [](auto& c) { (void)pex::explorer::load_options(c); }},
      [](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
        auto explorer =
            std::make_shared<ExplorerNode>(pex::explorer::load_options(config), ExplorerNode::Planning::kWorkerThread);
        const auto& options = explorer->options();
        if (options.keep_out)
          spdlog::info("keep-out: {} lines and {} areas, walls for every plan", options.keep_out_lines,
                       options.keep_out_areas);

        node.collect_counters([explorer]() -> const ExplorerNode& { return *explorer; });  // DAEMON_STATUS, the benchmark

        // The mission survives a restart (kill -9, a crash, a reboot).
        pex::runtime::keep_checkpoint(node, {options.checkpoint_file, options.checkpoint_period_s, "mission",
                                             [explorer](const std::string& text) { return explorer->restore(text); },
                                             [explorer] { return explorer->checkpoint_text(); }});
        // So does the way the robot drove, which tight plans and the way home follow.
        pex::runtime::keep_checkpoint(
            node, {options.trail_checkpoint_file, options.checkpoint_period_s, "trails",
                   [explorer](const std::string& bytes) { return explorer->restore_trails(bytes); },
                   [explorer] { return explorer->trail_checkpoint(); }});

        // Inputs the explorer refuses (std::invalid_argument) the node counts, logs and drops.
        node.subscribe<pex::polygon_map_t>(ch::kMap, [&node, explorer](const pex::polygon_map_t& msg) {
          explorer->on_map(msg, node.now_utime());
        });
        node.subscribe<pex::pose_t>(options.pose_channel, [&node, explorer](const pex::pose_t& msg) {
          explorer->on_pose(msg, node.now_utime());
        });
        node.subscribe<pex::slam_update_t>(ch::kSlamUpdate, [explorer](const pex::slam_update_t& msg) {
          explorer->on_slam_update(msg);
        });
        node.subscribe<pex::laser_scan_t>(ch::kLidarScan, [&node, explorer](const pex::laser_scan_t& msg) {
          explorer->on_scan(msg, node.now_utime());
        });
        node.subscribe<pex::mission_cmd_t>(ch::kMissionCmd, [&node, explorer](const pex::mission_cmd_t& msg) {
          const std::string why = explorer->on_command(msg, node.now_utime());
          spdlog::info("mission command {} from '{}'{}{}", static_cast<int>(msg.command), msg.source,
                       why.empty() ? "" : ": not applied: ", why);
        });
        node.watch_fd(explorer->plan_fd(), [&node, explorer] { explorer->on_plan_ready(node.now_utime()); });

        // Commands at a fixed rate: the mission's while MOVING or HOMING, zero
        // otherwise. The log tells each phase change and each new goal (not
        // the changing numbers of a stale input: the health says that).
        auto last_phase = std::make_shared<pex::planning::Phase>(pex::planning::Phase::kIdle);
        auto last_status = std::make_shared<std::string>();
        node.every(period_of(options.cmd_rate_hz), [&node, explorer, last_phase, last_status](std::int64_t now_utime) {
          node.publish(ch::kBaseCmd, explorer->step(now_utime));
          const auto& out = explorer->last_output();
          if (out.phase != *last_phase || (!out.degraded && out.status != *last_status)) {
            spdlog::info("{}: {}", pex::planning::to_string(out.phase), out.status);
            *last_phase = out.phase;
            *last_status = out.status;
          }
          if (out.degraded) {
            node.set_state(pex::daemon_status_t::STATE_DEGRADED, out.degraded_reason);
          } else {
            node.set_state(pex::daemon_status_t::STATE_OK);
          }
        });
        node.every(period_of(options.state_rate_hz), [&node, explorer](std::int64_t now_utime) {
          node.publish(ch::kExploreState, explorer->state_message(now_utime));
        });
        // The keep-out as every plan takes it (map frame), for pex-viewer and
        // the capture: drawn over the map, it shows where the robot holds the
        // lines to be, which is off the glass when the SLAM frame is. At
        // start and every 5 s, so a viewer or a recording started later has it.
        if (options.keep_out) {
          auto publish_keep_out = [&node, keep_out = options.keep_out](std::int64_t now_utime) {
            node.publish(ch::kKeepOut, pex::explorer::encode_map(*keep_out, now_utime));
          };
          publish_keep_out(node.now_utime());
          node.every(std::chrono::seconds(5), publish_keep_out);
        }
        node.on_shutdown([&node] { node.publish(ch::kBaseCmd, ExplorerNode::stop_command(node.now_utime())); });
      });
}
