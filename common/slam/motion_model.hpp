#pragma once
// GMapping's odometry motion model: the odometry step (expressed in the frame
// of the previous odometry pose) is perturbed with zero-mean Gaussian noise whose
// standard deviations grow with the step, then applied to the particle.
#include <random>

#include "geometry/pose2.hpp"

namespace pex::slam {

using geometry::Pose2;

struct MotionModelOptions {
  double srr = 0.1;  // translation std per metre of translation (m/m)
  double srt = 0.2;  // rotation std per metre of translation (rad/m)
  double str = 0.1;  // translation std per radian of rotation (m/rad)
  double stt = 0.2;  // rotation std per radian of rotation (rad/rad)
};

// Standard deviations (x, y, theta) of the noise for an odometry step.
Pose2 motion_noise_std(const Pose2& odometry_step, const MotionModelOptions& options);

// Draws the particle's new pose given the odometry step.
Pose2 sample_motion(const Pose2& pose, const Pose2& odometry_step, const MotionModelOptions& options,
                    std::mt19937_64& rng);

}  // namespace pex::slam
