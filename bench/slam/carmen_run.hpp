#pragma once
// Runs the filter library on a parsed CARMEN log the way the slam daemon does
// (odometry/scan pairing, filter, per-scan trajectory), without LCM, to measure
// the filter alone.
#include <vector>

#include "evaluation/carmen_log.hpp"
#include "evaluation/relations.hpp"
#include "slam/particle_filter.hpp"

namespace pex::bench {

struct CarmenRunResult {
  std::vector<evaluation::StampedPose> poses;  // one per scan after the first update
  std::int64_t updates = 0;
  std::int64_t resamplings = 0;
  std::int64_t matcher_evaluations = 0;
  double log_duration_s = 0.0;
};

// Odometry comes from the laser lines' odometry poses (as pex-carmen2lcm's
// default), or from ODOM lines when odometry_from_laser is false and the log has any.
CarmenRunResult run_filter_on_carmen(const evaluation::CarmenLog& log,
                                     const slam::ParticleFilterOptions& options,
                                     bool odometry_from_laser = true);

}  // namespace pex::bench
