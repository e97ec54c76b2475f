#pragma once
// Odometry that counts driving backwards as driving forwards, turned round.
//
// Some CARMEN logs (FR079 of the Kümmerle et al. 2009 benchmark) integrate the
// translational speed without its sign: where the ODOM lines' `tv` is negative
// the logged x, y still advance along the heading, in the ODOM lines and in the
// odometry poses embedded in the laser lines (which interpolate the ODOM lines).
// One such step puts the filter's prediction twice the step off, and along a
// corridor no scan match can tell (docs/slam.md, issue 13).
//
// correct_odometry_direction rebuilds the odometry from the ODOM lines' own
// steps: a step (ODOM line i-1 to i, in file order) whose mean speed
// (tv[i-1] + tv[i]) / 2 is negative while it moves forward along the heading
// (x > 0 in the frame of line i-1) has its translation reversed, its heading
// change kept; the steps are composed again from the first ODOM pose. Each laser
// line's odometry pose is re-placed at the same offset from the ODOM line
// nearest in time (the offset's translation reversed too where it lies on a
// reversed step), and its laser pose keeps its mounting offset.
//
// A log without ODOM lines, or whose steps agree with the sign of their speed
// (Intel's `tv` is always 0), comes out unchanged bit for bit; so do all poses
// before the first reversed step. Deterministic, no parameters.
#include <cstddef>

#include "evaluation/carmen_log.hpp"

namespace pex::evaluation {

struct OdometryDirectionResult {
  std::size_t reversed_steps = 0;       // ODOM steps whose translation was reversed
  std::size_t changed_laser_poses = 0;  // laser lines whose odometry pose changed
};

// Needs `log.order` (file order of the lines) as parse_carmen_log fills it.
OdometryDirectionResult correct_odometry_direction(CarmenLog& log);

}  // namespace pex::evaluation
