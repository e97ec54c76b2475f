// pex-slam: Rao-Blackwellized particle filter SLAM (GMapping's scheme).
// LIDAR_SCAN + ODOMETRY in; SLAM_UPDATE after every filter update, SLAM_POSE at
// odometry rate. Offline: `pex-slam --log IN.lcm --poses OUT.txt` feeds the log
// through the same handlers and writes one `timestamp_s x y theta` per scan
// (each update's correction spread over the scans before it; docs/slam.md)
// (and with --checkpoint-out the filter's checkpoint at the log's end).
#include <cstdio>
#include <fstream>
#include <chrono>
#include <memory>

#include <pex/daemon_status_t.hpp>
#include <spdlog/spdlog.h>

#include "runtime/channels.hpp"
#include "runtime/checkpoint.hpp"
#include "runtime/daemon.hpp"
#include "runtime/files.hpp"
#include "runtime/input_watch.hpp"
#include "slam_options.hpp"

namespace ch = pex::runtime::channels;
using pex::slam_daemon::SlamNode;

int main(int argc, char** argv) {
  std::string poses_path;
  std::string checkpoint_out;
  bool poses_carried_forward = false;
  pex::runtime::DaemonInfo info{"slam", "Rao-Blackwellized particle filter SLAM"};
  info.supports_replay = true;
  info.load_options = [](auto& c) { (void)pex::slam_daemon::load_options(c); };
  info.add_options = [&](CLI::App& app) {
    app.add_option("--poses", poses_path, "offline: write the best trajectory, one `t x y theta` per scan");
    app.add_flag("--poses-carried-forward", poses_carried_forward,
                 "offline: a scan between updates gets its update's pose carried forward by odometry (as the robot "
                 "knew it then), not the next update's correction spread over the scans before it");
    app.add_option("--checkpoint-out", checkpoint_out, "offline: write the filter's checkpoint at the end of the log");
  };
  return pex::runtime::run_daemon(argc, argv, info, [&](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
    auto options = pex::slam_daemon::load_options(config);
    options.record_trajectory = !poses_path.empty();
    options.spread_corrections = !poses_carried_forward;
    pex::slam_daemon::SlamOutputs outputs;
    outputs.publish_update = [&node](const pex::slam_update_t& msg) {
      pex::slam_update_t stamped = msg;  // publication time: wall clock live, log time in replay
      stamped.utime = node.now_utime();
      node.publish(ch::kSlamUpdate, stamped);
    };
    outputs.publish_pose = [&node](const pex::pose_t& msg) { node.publish(ch::kSlamPose, msg); };
    auto slam = std::make_shared<SlamNode>(options, outputs);
    // The filter survives a restart: the same epoch and generations go on, so
    // the mapper keeps its maps. Saved on stop before the flush below: scans
    // still waiting for odometry stay waiting in the checkpoint.
    pex::runtime::keep_checkpoint(node, {options.checkpoint_file, options.checkpoint_period_s, "filter",
                                         [slam](const std::string& bytes) { return slam->restore(bytes); },
                                         [slam] { return slam->checkpoint(); }});
    // Health: without scans or odometry the filter stands still (DEGRADED, says which).
    auto watch = std::make_shared<pex::runtime::InputWatch>();
    const auto timeout_us = static_cast<std::int64_t>(options.input_timeout_s * 1e6);
    watch->expect(std::string(ch::kLidarScan), timeout_us);
    watch->expect(std::string(ch::kOdometry), timeout_us);
    node.every(std::chrono::milliseconds(250), [&node, watch](std::int64_t) {
      const std::string why = watch->stale(node.monotonic_us());
      node.set_state(why.empty() ? pex::daemon_status_t::STATE_OK : pex::daemon_status_t::STATE_DEGRADED, why);
    });
    node.collect_counters([slam]() -> const SlamNode& { return *slam; });
    // Content the filter refuses (std::invalid_argument) the node counts, logs and drops.
    node.subscribe<pex::odometry_t>(ch::kOdometry, [slam, &node, watch](const pex::odometry_t& msg) {
      watch->seen(ch::kOdometry, node.monotonic_us());  // alive, even when a reading is held
      slam->on_odometry(msg);
    });
    node.subscribe<pex::laser_scan_t>(ch::kLidarScan, [slam, &node, watch](const pex::laser_scan_t& msg) {
      slam->on_scan(msg);
      watch->seen(ch::kLidarScan, node.monotonic_us());
    });
    node.on_shutdown([slam, &poses_path, &checkpoint_out] {
      slam->flush();
      spdlog::info("{} filter updates, {} odometry steps replaced by the odometry check, {} along the odometry "
                   "where the scan constrained no position; odometry drift {:.5f} rad/m, turn scale {:+.4f} "
                   "({} steps of evidence)",
                   slam->filter().generation() + 1, slam->filter().corrected_odometry_steps(),
                   slam->filter().unconstrained_updates(), slam->filter().odometry_drift().drift_rad_per_m(),
                   slam->filter().odometry_drift().turn_scale(), slam->filter().odometry_drift().observations());
      if (!checkpoint_out.empty()) {
        const std::string bytes = slam->checkpoint();
        if (const auto why = pex::runtime::write_file_atomically(checkpoint_out, bytes); !why.empty())
          spdlog::error("{}", why);
        else
          spdlog::info("wrote the filter's checkpoint ({} bytes, generation {}) to {}", bytes.size(),
                       slam->filter().generation(), checkpoint_out);
      }
      if (poses_path.empty()) return;
      std::ofstream out(poses_path);
      out << slam->trajectory_text();
      if (!out) spdlog::error("cannot write {}", poses_path);
      else spdlog::info("wrote {} poses to {}", slam->scans_processed(), poses_path);
    });
  });
}
