#pragma once
// The last line of defence against driving into a wall: the live laser scan,
// in the robot's own frame, bounds the command so that the robot can brake
// before its body touches anything the laser sees on the way it is driving.
// The planner keeps paths clear of the *map's* walls, but the map and the pose
// come from SLAM, which can be a decimetre or more off; the scan cannot.
// The way is the arc the command drives (curvature omega / v), not a straight
// line: a robot arcing round a corner meets the corner with its side, where a
// straight-ahead check sees nothing. Pure: points in, command out; no clock,
// no I/O.
#include <span>

#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct ScanGuardOptions {
  double body_radius_m = 0.25;     // the robot's disk itself, no margin
  double margin_m = 0.03;          // kept between the body and a return when stopped
  double max_decel_mps2 = 0.5;     // braking the guard may count on
  // How long the robot keeps its speed after a command before it brakes: the
  // control period, the base driver and the drives. An intel mission touched
  // a wall at its side while the guard's commands went 0.38 -> 0.14 -> 0 m/s
  // in 0.4 s and the robot, 0.18 m/s a tenth of a second after the zero, went
  // on into it (simulated time at x10, where a loaded machine's few ms of
  // delay are tens of ms).
  double latency_s = 0.2;
};

// The arc length the robot (a disk of body_radius_m centred at the origin,
// heading along +x) can drive forward on the circle of signed curvature
// curvature_per_m (positive: to the left; 0: straight ahead) before it touches
// one of the points (robot frame); +infinity when it never does. A point the
// body overlaps already gives 0 when it lies ahead of the centre (driving on
// would press into it by more than 5 mm) and is ignored otherwise (driving on
// moves away from it). Non-finite points are ignored.
double free_distance_along_arc(std::span<const mapping::Point> points_robot_frame, double curvature_per_m,
                               double body_radius_m);

// free_distance_along_arc for straight motion.
double free_distance_ahead(std::span<const mapping::Point> points_robot_frame, double body_radius_m);

// The largest forward speed v from which the robot stops margin_m short of the
// first point in its way, driving on at v for latency_s before braking at a:
// v t + v^2 / (2 a) = d - margin; 0 within the margin.
double max_safe_speed(double free_distance_m, const ScanGuardOptions& options);

struct GuardedCommand {
  double v_mps = 0.0;
  double omega_radps = 0.0;
  bool limited = false;  // the guard changed the command
};

// The command the guard lets through. A forward command keeps its curvature
// (the follower's path) at a speed from which the robot can brake on that arc
// margin_m short of the first return, counting travelled_since_scan_m (how far
// the robot may have moved since the scan was taken) as already used up. When
// the arc is blocked at once the robot turns on the spot at the commanded
// turn rate instead: a disk turning in place sweeps nothing new. Commands
// that do not drive forward pass unchanged.
GuardedCommand guard_command(std::span<const mapping::Point> points_robot_frame, double v_mps, double omega_radps,
                             double travelled_since_scan_m, const ScanGuardOptions& options);

}  // namespace pex::planning
