#include "carmen_run.hpp"

#include <cmath>

#include "slam/odometry_sync.hpp"
#include "slam/trajectory_recorder.hpp"

namespace pex::bench {
namespace {

std::int64_t to_utime(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e6)); }

}  // namespace

CarmenRunResult run_filter_on_carmen(const evaluation::CarmenLog& log,
                                     const slam::ParticleFilterOptions& options,
                                     bool odometry_from_laser_requested,
                                     const slam::OdometrySyncOptions& sync_options,
                                     const std::function<void(const slam::ParticleFilter&, std::int64_t)>&
                                         after_update) {
  CarmenRunResult result;
  slam::ParticleFilter filter(options);
  slam::OdometrySync sync(sync_options);
  slam::TrajectoryRecorder recorder;
  const bool odometry_from_laser = odometry_from_laser_requested || log.odometry.empty();
  auto feed = [&](std::vector<slam::PairedScan> ready) {
    for (const slam::PairedScan& paired : ready) {
      if (filter.process(paired.scan, paired.odometry)) {
        sync.observe_update(paired.scan.utime, filter.best_turn_at_last_update());
        result.odometry_lead_us_per_update.push_back(sync.lead_us());
        ++result.updates;
        result.resamplings += filter.last_update().resampled;
        result.matcher_evaluations += filter.last_update().matcher_evaluations;
        if (after_update) after_update(filter, paired.scan.utime);
      }
      recorder.record(paired.scan.utime, filter, paired.odometry);
    }
  };
  double first = -1.0;
  double last = 0.0;
  for (const auto& entry : log.order) {
    if (entry.is_laser) {
      const evaluation::CarmenLaser& laser = log.lasers[entry.index];
      if (first < 0) first = laser.timestamp_s;
      last = laser.timestamp_s;
      if (odometry_from_laser) sync.add_odometry(to_utime(laser.timestamp_s), laser.odometry);
      slam::RangeScan scan;
      scan.utime = to_utime(laser.timestamp_s);
      scan.angle_min_rad = laser.angle_min_rad;
      scan.angle_increment_rad = laser.angle_increment_rad;
      scan.range_min_m = 0.0;
      scan.range_max_m = laser.max_range_m;
      scan.ranges_m = laser.ranges_m;
      sync.add_scan(std::move(scan));
    } else if (!odometry_from_laser) {
      const evaluation::CarmenOdometry& odom = log.odometry[entry.index];
      sync.add_odometry(to_utime(odom.timestamp_s), odom.pose);
    }
    feed(sync.take_ready());
  }
  feed(sync.flush());
  for (const slam::TimedPose& p : recorder.resolve(filter))
    result.poses.push_back({static_cast<double>(p.utime) * 1e-6, p.pose});
  for (const slam::TimedPose& p : recorder.resolve(filter, true))
    result.spread_poses.push_back({static_cast<double>(p.utime) * 1e-6, p.pose});
  result.log_duration_s = last - first;
  result.odometry_lead_us = sync.lead_us();
  result.corrected_odometry_steps = filter.corrected_odometry_steps();
  return result;
}

}  // namespace pex::bench
