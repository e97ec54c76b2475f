#include "slam/motion_model.hpp"

#include <cmath>

namespace pex::slam {

Pose2 motion_noise_std(const Pose2& d, const MotionModelOptions& o) {
  // As GMapping: a lateral term of 0.3 srr couples x and y noise.
  const double sxy = 0.3 * o.srr;
  return {o.srr * std::abs(d.x_m) + o.str * std::abs(d.theta_rad) + sxy * std::abs(d.y_m),
          o.srr * std::abs(d.y_m) + o.str * std::abs(d.theta_rad) + sxy * std::abs(d.x_m),
          o.stt * std::abs(d.theta_rad) + o.srt * std::hypot(d.x_m, d.y_m)};
}

Pose2 sample_motion(const Pose2& pose, const Pose2& step, const MotionModelOptions& options,
                    std::mt19937_64& rng) {
  const Pose2 sigma = motion_noise_std(step, options);
  std::normal_distribution<double> normal(0.0, 1.0);
  Pose2 noisy = step;
  noisy.x_m += sigma.x_m * normal(rng);
  noisy.y_m += sigma.y_m * normal(rng);
  noisy.theta_rad = geometry::wrap_angle(noisy.theta_rad + sigma.theta_rad * normal(rng));
  return compose(pose, noisy);
}

}  // namespace pex::slam
