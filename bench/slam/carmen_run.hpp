#pragma once
// Runs the filter library on a parsed CARMEN log the way the slam daemon does
// (odometry/scan pairing, filter, per-scan trajectory), without LCM, to measure
// the filter alone.
#include <functional>
#include <vector>

#include "evaluation/carmen_log.hpp"
#include "evaluation/relations.hpp"
#include "slam/odometry_sync.hpp"
#include "slam/particle_filter.hpp"

namespace pex::bench {

struct CarmenRunResult {
  std::vector<evaluation::StampedPose> poses;  // one per scan after the first update
  std::vector<evaluation::StampedPose> spread_poses;  // the same with the corrections spread between updates
  std::int64_t updates = 0;
  std::int64_t resamplings = 0;
  std::int64_t matcher_evaluations = 0;
  double log_duration_s = 0.0;
  std::int64_t odometry_lead_us = 0;           // the pairing's lead at the end
  std::int64_t corrected_odometry_steps = 0;  // updates whose odometry step the check replaced
  std::vector<std::int64_t> odometry_lead_us_per_update;  // the pairing's lead after each update
};

// Odometry comes from the laser lines' odometry poses (as pex-carmen2lcm's
// default), or from ODOM lines when odometry_from_laser is false and the log has any.
CarmenRunResult run_filter_on_carmen(const evaluation::CarmenLog& log,
                                     const slam::ParticleFilterOptions& options,
                                     bool odometry_from_laser = true,
                                     const slam::OdometrySyncOptions& sync = {},
                                     const std::function<void(const slam::ParticleFilter&, std::int64_t)>&
                                         after_update = {});

}  // namespace pex::bench
