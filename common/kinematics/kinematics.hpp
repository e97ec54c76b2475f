#pragma once
// Differential-drive kinematics: body velocity commands to wheel speeds with
// limits, and encoder counts to odometry. Pure functions and small state
// machines; time is passed in.
#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "geometry/pose2.hpp"

namespace pex::kinematics {

// Geometry and encoder of the base. The encoder sits on the motor, before the
// gearbox: one wheel turn = counts_per_rev * gear_ratio counts.
struct DriveGeometry {
  double wheel_radius_m = 0.1;
  double wheel_base_m = 0.5;        // distance between the wheel contact points
  double counts_per_rev = 4096.0;   // motor encoder counts per motor revolution
  double gear_ratio = 20.0;         // motor revolutions per wheel revolution

  double counts_per_m() const;      // counts per metre of wheel travel
  // Empty when every value is finite and positive, else what is wrong.
  std::string validate() const;
};

struct WheelSpeeds {
  double left_mps = 0.0;   // wheel surface speed, m/s
  double right_mps = 0.0;
};

struct BodyVelocity {
  double v_mps = 0.0;
  double omega_radps = 0.0;
};

WheelSpeeds to_wheels(const DriveGeometry& geometry, BodyVelocity body);
BodyVelocity to_body(const DriveGeometry& geometry, WheelSpeeds wheels);

// Limits a command: forward speed, yaw rate, each wheel's speed (scaling both
// wheels together so the curvature is kept) and each wheel's acceleration.
class VelocityLimiter {
 public:
  struct Options {
    double max_speed_mps = 1.0;
    double max_omega_radps = 2.0;
    double max_wheel_speed_mps = 1.2;
    double max_wheel_accel_mps2 = 1.0;
  };
  VelocityLimiter(DriveGeometry geometry, Options options);

  // Wheel speeds for `command` after `dt_s` since the previous call. NaN or
  // infinite commands are treated as stop. The output never changes faster
  // than max_wheel_accel_mps2 allows.
  WheelSpeeds step(BodyVelocity command, double dt_s);
  WheelSpeeds last() const { return last_; }
  void reset() { last_ = {}; }

 private:
  DriveGeometry geometry_;
  Options options_;
  WheelSpeeds last_;
};

// Integrates encoder counts into a pose with a covariance that grows with the
// distance travelled and the angle turned. Counts are int32 and may wrap:
// deltas are computed modulo 2^32.
class OdometryIntegrator {
 public:
  struct Options {
    // Standard deviation growth: per sqrt(metre) of travel along and across,
    // and per sqrt(radian) of turning (and per sqrt(metre), for theta).
    double sigma_translation_per_sqrt_m = 0.05;
    double sigma_rotation_per_sqrt_rad = 0.05;
    double sigma_rotation_per_sqrt_m = 0.02;
    // A per-update jump beyond this (m) is treated as an encoder reset, not motion.
    double max_wheel_step_m = 0.5;
    // v and omega are averaged over this much time: encoder readings arrive
    // with the bus's timing jitter, which a one-update difference amplifies.
    std::int64_t velocity_window_us = 50'000;
  };

  struct State {
    geometry::Pose2 pose;  // heading in (-pi, pi]
    double v_mps = 0.0;
    double omega_radps = 0.0;
    std::array<double, 9> covariance{};  // row-major over (x, y, theta)
    double distance_m = 0.0;              // travelled so far (absolute)
  };

  OdometryIntegrator(DriveGeometry geometry, Options options);

  // Feeds the counts read at time_us. The first call only sets the baseline.
  // Returns false (and re-baselines) when a jump is implausible.
  bool update(std::int32_t left_counts, std::int32_t right_counts, std::int64_t time_us);
  // Forget the baseline (after a drive restarted and its counter was reset).
  void rebaseline() { have_baseline_ = false; }
  const State& state() const { return state_; }
  std::uint64_t rejected_jumps() const { return rejected_jumps_; }

 private:
  DriveGeometry geometry_;
  Options options_;
  State state_;
  bool have_baseline_ = false;
  std::int32_t left_ = 0, right_ = 0;
  std::int64_t time_us_ = 0;
  std::uint64_t rejected_jumps_ = 0;
  struct Sample {
    std::int64_t time_us;
    double distance_m;   // signed, cumulative
    double heading_rad;  // unwrapped, cumulative
  };
  std::deque<Sample> history_;
  double signed_distance_m_ = 0.0;
  double heading_rad_ = 0.0;
};

}  // namespace pex::kinematics
