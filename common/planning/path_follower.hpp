#pragma once
// Pure-pursuit path following for a differential-drive base: (pose, path) ->
// (v, omega) within speed and acceleration limits. The robot turns on the
// spot when the path lies far off its heading (a differential drive can, and
// an arc would sweep wide of a path planned for a disk), and slows down so
// that it can stop at the end of the path.
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/scan_polygon.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

using mapping::Point;
using geometry::Pose2;

struct FollowerOptions {
  double max_speed_mps = 0.4;
  // Near the goal the speed never drops below this, so the robot arrives.
  double min_speed_mps = 0.05;
  double max_omega_radps = 1.0;
  double max_accel_mps2 = 0.5;             // also the braking used to slow for the goal
  double max_angular_accel_radps2 = 2.0;
  double lookahead_m = 0.5;                // pure-pursuit look-ahead distance
  // Hysteresis of turning on the spot: start above the first heading error,
  // drive again below the second.
  double turn_in_place_rad = 0.8;
  double turn_in_place_exit_rad = 0.3;
  double turn_gain_per_s = 2.0;            // omega = gain * heading error when turning on the spot
  double goal_tolerance_m = 0.2;           // the path's end counts as reached this close
  // The look-ahead point stops at the next path vertex until the robot is
  // this close to it (or past it): the most a corner is cut.
  double corner_tolerance_m = 0.1;
};

struct VelocityCommand {
  double v_mps = 0.0;
  double omega_radps = 0.0;
};

// The way back along `trail` (the robot's positions, oldest first, its
// position now last): the trail reversed, as far as max_length_m along it.
// Empty for a trail of fewer than two points.
std::vector<Point> way_back(const std::vector<Point>& trail, double max_length_m);

class PathFollower {
 public:
  explicit PathFollower(FollowerOptions options = {});

  // Follows `path` from now on (an empty path: stand still). The last command
  // is kept, so a replanned path does not make the robot jerk.
  void set_path(std::vector<Point> path);
  void clear() { set_path({}); }
  // Forgets the last command (the robot was stopped by someone else).
  void stop() { last_ = {}; turning_ = false; }

  // The next command; dt_s is the time since the previous one (limits the
  // change of v and omega). Zero once the end of the path is reached.
  VelocityCommand update(const Pose2& pose, double dt_s);

  // Turns on the spot toward `heading_rad` (v = 0; omega from turn_gain_per_s
  // within the limits), e.g. to face the frontier a goal was chosen for.
  VelocityCommand turn_to(const Pose2& pose, double heading_rad, double dt_s);

  bool goal_reached() const { return reached_; }
  bool turning_in_place() const { return turning_; }
  const std::vector<Point>& path() const { return path_; }
  const VelocityCommand& last_command() const { return last_; }
  const FollowerOptions& options() const { return options_; }

 private:
  FollowerOptions options_;
  std::vector<Point> path_;
  std::vector<double> arc_;   // arc length at each path point
  std::size_t segment_ = 0;   // progress: the segment being followed, never moves back
  bool reached_ = false;
  bool turning_ = false;
  VelocityCommand last_;
};

}  // namespace pex::planning
