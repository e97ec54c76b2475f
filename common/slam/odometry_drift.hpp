#pragma once
// The systematic part of a differential drive's heading error, learnt from
// the filter's own matches. Wheels of slightly different radii bend the
// odometry's heading by a fixed amount per metre driven, a wheel base that
// is slightly off scales every turn; neither averages out, and the motion
// model takes its noise as zero-mean. On ground the particles' maps already
// hold, the matcher corrects it; on new ground the prediction is what the
// hill climb starts from and the proposal's motion prior pulls toward, so
// part of the bias can stay in the poses (docs/slam.md, "Odometry drift").
//
// Model: over a step of forward travel d (signed: backwards is negative, and
// so is the drift it brings) and odometry turn dtheta, the true turn is
// dtheta + drift_per_m * d + turn_scale * dtheta. The two are estimated by
// least squares with exponential forgetting over the steps the scan
// constrained (the best particle's matched turn against the odometry's), with
// a ridge toward 0 so that a few steps move them little, and bounded.
// Pure: steps in, estimate out.
#include <cstdint>

#include "archive/byte_archive.hpp"
#include "geometry/pose2.hpp"

namespace pex::slam {

struct OdometryDriftOptions {
  // Take the estimate out of every update's step. Off: estimated and shown
  // only (DAEMON_STATUS, pex-slam's last line), for calibrating the base.
  // On the simulator's base correcting it gave no reliable gain: less drift
  // on replayed laps along a bare wall, not live, none elsewhere
  // (docs/slam.md, "Odometry drift").
  bool correct = false;
  // Each step's weight decays by this factor per later step (0.998: the
  // last ~500 updates, about 250 m at 0.5 m per update).
  double forgetting = 0.998;
  // The ridge: the estimate is held toward 0 as if this much travel (m) and
  // turning (rad) always showed no drift (it shrinks a steady estimate by
  // about ridge / (ridge + the window's evidence): 5 % with the defaults on
  // a base driving 0.5 m per update).
  double prior_travel_m = 5.0;
  double prior_turn_rad = 2.0;
  // Bounds of the estimate (a base beyond them needs calibrating, not this).
  double max_drift_rad_per_m = 0.05;
  double max_turn_scale = 0.1;
  // A step whose matched turn differs from the odometry's by more than this
  // is not evidence of a drift (a slip, a wrong match) and is left out.
  double max_step_residual_rad = 0.05;
};

class OdometryDrift {
 public:
  explicit OdometryDrift(const OdometryDriftOptions& options = {});

  // One step's evidence: the odometry's forward travel (m, signed: the
  // step's x in the robot frame) and turn (rad) over an update, and the
  // turn the scan matching gave for the same step.
  // Returns false when the step was left out (max_step_residual_rad).
  bool observe(double odometry_forward_m, double odometry_turn_rad, double matched_turn_rad);

  // The odometry step with its heading corrected by the estimate (the
  // translation is kept: the drift model is about heading only); the step
  // as it is when `correct` is off.
  geometry::Pose2 correct(const geometry::Pose2& odometry_step) const;

  double drift_rad_per_m() const { return drift_rad_per_m_; }
  double turn_scale() const { return turn_scale_; }
  std::int64_t observations() const { return observations_; }
  std::int64_t refused() const { return refused_; }

  // Its state in a checkpoint (ParticleFilter::checkpoint).
  void write(archive::ByteWriter& out) const;
  void read(archive::ByteReader& in);

 private:
  void solve();

  OdometryDriftOptions options_;
  // Forgotten sums of phi * phi^T and phi * residual, phi = (d, dtheta).
  double a_dd_ = 0.0, a_dt_ = 0.0, a_tt_ = 0.0, b_d_ = 0.0, b_t_ = 0.0;
  double drift_rad_per_m_ = 0.0, turn_scale_ = 0.0;
  std::int64_t observations_ = 0, refused_ = 0;
};

}  // namespace pex::slam
