// pex-viewer: a live web page of the mission. MAP, a pose, LIDAR_SCAN,
// EXPLORE_STATE, KEEP_OUT and DAEMON_STATUS in; the page (and /api/state, /events) out
// on bind_address:port; the page's mission buttons out as MISSION_CMD. What
// is shown is kept by ViewerState (viewer_state.hpp); HTTP is web_server.hpp.
#include <chrono>
#include <map>
#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/mission_cmd_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>

#include "runtime/channels.hpp"
#include "runtime/daemon.hpp"
#include "runtime/input_watch.hpp"
#include "viewer_options.hpp"
#include "web_server.hpp"

namespace ch = pex::runtime::channels;

namespace pex::viewer {
extern const char* const kPage;  // index.html, built in (viewer_page.cpp)
}

int main(int argc, char** argv) {
  return pex::runtime::run_daemon(
      argc, argv, {.name = "viewer",
       .description = "live web view of the mission: map, robot, scan, plan, health; mission buttons",
       .load_options = [](auto& c) { (void)pex::viewer::load_options(c); }},
      [](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
        const auto options = pex::viewer::load_options(config);
        auto state = std::make_shared<pex::viewer::ViewerState>(options.state);
        std::shared_ptr<pex::viewer::WebServer> web;
        try {
          web = std::make_shared<pex::viewer::WebServer>(
              pex::viewer::WebServerOptions{options.bind_address, options.port, options.max_clients},
              pex::viewer::kPage);
        } catch (const std::runtime_error& e) {
          throw pex::runtime::Unavailable(e.what());  // exit 69: systemd retries
        }
        spdlog::info("serving http://{}:{}/", options.bind_address, options.port);

        auto watch = std::make_shared<pex::runtime::InputWatch>();
        const auto timeout_us = static_cast<std::int64_t>(options.input_timeout_s * 1e6);
        watch->expect(std::string(ch::kMap), timeout_us);
        watch->expect(options.pose_channel, timeout_us);
        // A refused message (std::invalid_argument) leaves the state as it was; the node counts and logs it.
        node.subscribe<pex::polygon_map_t>(ch::kMap, [&node, state, watch](const pex::polygon_map_t& m) {
          state->on_map(m);
          watch->seen(ch::kMap, node.monotonic_us());
        });
        node.subscribe<pex::pose_t>(options.pose_channel,
                                    [&node, state, watch, channel = options.pose_channel](const pex::pose_t& p) {
                                      state->on_pose(p);
                                      watch->seen(channel, node.monotonic_us());
                                    });
        node.subscribe<pex::polygon_map_t>(ch::kKeepOut, [state](const pex::polygon_map_t& k) { state->on_keep_out(k); });
        node.subscribe<pex::laser_scan_t>(ch::kLidarScan, [state](const pex::laser_scan_t& s) { state->on_scan(s); });
        node.subscribe<pex::explore_state_t>(ch::kExploreState,
                                             [state](const pex::explore_state_t& s) { state->on_explore_state(s); });
        node.subscribe<pex::daemon_status_t>(ch::kDaemonStatus, [&node, state](const pex::daemon_status_t& s) {
          state->on_status(s, node.now_utime());
        });
        node.collect_counters([web] { return web->counters(); });

        // The page's buttons: MISSION_CMD, as pex-mission sends it.
        node.watch_fd(web->command_fd(), [&node, web] {
          // Copies (std::int8_t{...}): the pair constructor takes references,
          // and the generated constants have no definition to refer to.
          using C = pex::mission_cmd_t;
          static const std::map<std::string, std::int8_t> kCodes = {
              {"start", std::int8_t{C::CMD_START}}, {"pause", std::int8_t{C::CMD_PAUSE}},
              {"resume", std::int8_t{C::CMD_RESUME}}, {"home", std::int8_t{C::CMD_HOME}},
              {"stop", std::int8_t{C::CMD_STOP}}};
          for (const auto& name : web->take_commands()) {
            pex::mission_cmd_t cmd{};
            cmd.utime = node.now_utime();
            cmd.command = kCodes.at(name);
            cmd.source = "pex-viewer";
            node.publish(ch::kMissionCmd, cmd);
            ++node.counter("mission_commands_sent");
            spdlog::info("mission command '{}' from the page", name);
          }
        });

        // The pages' updates, and the viewer's health.
        const auto period = std::chrono::microseconds(static_cast<std::int64_t>(1e6 / options.update_rate_hz));
        auto map_sent = std::make_shared<std::int64_t>(-1);
        node.every(period, [&node, state, web, watch, map_sent](std::int64_t now_utime) {
          const auto version = state->map_version();
          std::string map_json;
          if (version != *map_sent) map_json = state->map_json().dump();
          web->publish(version, std::move(map_json), state->live_json(now_utime).dump());
          *map_sent = version;
          node.counter("map_version") = version;
          const std::string why = watch->stale(node.monotonic_us());
          node.set_state(why.empty() ? pex::daemon_status_t::STATE_OK : pex::daemon_status_t::STATE_DEGRADED, why);
        });
      });
}
