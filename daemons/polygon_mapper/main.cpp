// pex-polygon-mapper: LIDAR_SCAN + a pose source (ODOMETRY, SIM_TRUTH, or
// SLAM_UPDATE with one map per particle) -> the typed polygonal map (MAP). All
// mapping is in common/mapping and common/particle_maps; this file only wires
// messages to the Mapper (mapper.hpp).
#include <chrono>
#include <memory>

#include <pex/daemon_status_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/slam_update_t.hpp>
#include <spdlog/spdlog.h>

#include "initial_map.hpp"
#include "mapper.hpp"
#include "runtime/channels.hpp"
#include "runtime/checkpoint.hpp"
#include "runtime/daemon.hpp"
#include "runtime/input_watch.hpp"

namespace ch = pex::runtime::channels;
using pex::polygon_mapper::Mapper;

int main(int argc, char** argv) {
  pex::runtime::DaemonInfo info{"polygon_mapper", "typed polygonal map (MAP) from LIDAR_SCAN and a pose source"};
  info.supports_replay = true;
  info.load_options = [](auto& c) { (void)pex::polygon_mapper::load_options(c); };
  return pex::runtime::run_daemon(argc, argv, info, [](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
    auto mapper = std::make_shared<Mapper>(pex::polygon_mapper::load_options(config));
    // The map survives a restart: published at once from the checkpoint, and
    // with pose_source "slam" continued when SLAM's updates come (same epoch).
    const bool restored = pex::runtime::keep_checkpoint(
        node, {mapper->options().checkpoint_file, mapper->options().checkpoint_period_s, "map",
               [mapper](const std::string& bytes) { return mapper->restore(bytes); },
               [mapper] { return mapper->checkpoint(); }});
    // Else from a saved map (initial_map_file), if one is configured.
    if (!restored) pex::polygon_mapper::start_from_initial_map(*mapper);
    // Health: without scans or poses the map stands still (DEGRADED, says which).
    // With SLAM, SLAM_POSE says it is there: SLAM_UPDATE comes only after
    // 0.5 m or 0.25 rad, or with the robot standing, so a robot creeping to a
    // goal went 3-5 s without one, a dozen times a mission, and the mapper
    // called its pose source away each time.
    const std::string& source = mapper->options().pose_source;
    const std::string pose_channel(source == "slam"       ? ch::kSlamPose
                                   : source == "odometry" ? ch::kOdometry
                                                          : ch::kSimTruth);
    auto watch = std::make_shared<pex::runtime::InputWatch>();
    const auto timeout_us = static_cast<std::int64_t>(mapper->options().input_timeout_s * 1e6);
    watch->expect(std::string(ch::kLidarScan), timeout_us);
    watch->expect(pose_channel, timeout_us);
    node.collect_counters([mapper]() -> const Mapper& { return *mapper; });
    // MAP (planning map) and, unless switched off, MAP_FREE (explored free space).
    auto publish_maps = [&node, mapper](std::int64_t now_utime) {
      if (auto msg = mapper->map_message(now_utime)) node.publish(ch::kMap, *msg);
      if (mapper->options().publish_free_space)
        if (auto msg = mapper->free_space_message(now_utime)) node.publish(ch::kMapFree, *msg);
    };
    // Content the mapper refuses (std::invalid_argument) the node counts, logs and drops.
    node.subscribe<pex::laser_scan_t>(ch::kLidarScan, [&node, mapper, watch](const pex::laser_scan_t& scan) {
      mapper->on_scan(scan);
      watch->seen(ch::kLidarScan, node.monotonic_us());
    });
    if (source == "slam") {
      node.subscribe<pex::pose_t>(ch::kSlamPose, [&node, watch](const pex::pose_t&) {
        watch->seen(ch::kSlamPose, node.monotonic_us());
      });
      node.subscribe<pex::slam_update_t>(ch::kSlamUpdate, [&node, mapper, publish_maps](const pex::slam_update_t& update) {
        const auto epoch_changes = mapper->counters().slam_epoch_changes;
        const bool switched = mapper->on_slam_update(update);
        if (mapper->counters().slam_epoch_changes != epoch_changes)
          spdlog::warn("SLAM started afresh (epoch {}): its frame is not the old map's, which is dropped", update.epoch);
        // A new best particle: its map goes out now, consistent with its trajectory.
        if (switched) publish_maps(node.now_utime());
      });
    } else if (source == "odometry") {
      node.subscribe<pex::odometry_t>(ch::kOdometry, [&node, mapper, watch](const pex::odometry_t& odom) {
        mapper->on_pose({odom.utime, {odom.x, odom.y, odom.theta}});
        watch->seen(ch::kOdometry, node.monotonic_us());
      });
    } else {
      node.subscribe<pex::pose_t>(ch::kSimTruth, [&node, mapper, watch](const pex::pose_t& pose) {
        mapper->on_pose({pose.utime, {pose.x, pose.y, pose.theta}});
        watch->seen(ch::kSimTruth, node.monotonic_us());
      });
    }
    const auto period = std::chrono::microseconds(static_cast<std::int64_t>(1e6 / mapper->options().publish_rate_hz));
    node.every(period, publish_maps);
    // A laser blind in some sector (mapping::BlindBeams) is DEGRADED too: the
    // map goes on, but the operator should look at the window.
    node.every(std::chrono::milliseconds(250), [&node, watch, mapper](std::int64_t) {
      std::string why = watch->stale(node.monotonic_us());
      if (why.empty()) why = mapper->blind_laser_reason();
      node.set_state(why.empty() ? pex::daemon_status_t::STATE_OK : pex::daemon_status_t::STATE_DEGRADED, why);
    });
  });
}
