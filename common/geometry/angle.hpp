#pragma once
// Angle wraps: the one place an angle is brought into a range.
//
// Both are exact: std::fmod returns angle - k * 2pi without rounding, and the
// one correction by 2pi that may follow is exact too (Sterbenz: its operands
// are within a factor of two of each other), so the result is the input less
// a whole number of (double) 2pi.
#include <cmath>
#include <numbers>

namespace pex::geometry {

// The angle in (-pi, pi] equal to `angle_rad` modulo 2pi: -pi gives pi.
// NaN and +-inf give NaN (a wrap does not make a bad value good; callers check
// finiteness where the input comes in).
inline double wrap_angle(double angle_rad) {
  if (angle_rad > -std::numbers::pi && angle_rad <= std::numbers::pi) return angle_rad;
  angle_rad = std::fmod(angle_rad, 2.0 * std::numbers::pi);
  if (angle_rad <= -std::numbers::pi) angle_rad += 2.0 * std::numbers::pi;
  if (angle_rad > std::numbers::pi) angle_rad -= 2.0 * std::numbers::pi;
  return angle_rad;
}

// The angle in [0, 2pi] equal to `angle_rad` modulo 2pi, for counter-clockwise
// sweeps (from one direction to another, turning left). 2pi comes out only for
// an angle less than 4.4e-16 (half a unit in the last place of 2pi) below a
// multiple of 2pi, whose wrap rounds up to 2pi.
// NaN and +-inf give NaN.
inline double wrap_angle_positive(double angle_rad) {
  angle_rad = std::fmod(angle_rad, 2.0 * std::numbers::pi);
  if (angle_rad < 0.0) angle_rad += 2.0 * std::numbers::pi;
  return angle_rad;
}

}  // namespace pex::geometry
