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
#include <algorithm>
#include <span>
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/blind_beams.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct ScanGuardOptions {
  double body_radius_m = 0.25;     // the robot's disk itself, no margin
  double margin_m = 0.03;          // kept between the body and a return when stopped
  // A return this near the side of the band the body sweeps holds the robot
  // to creep_speed_mps: the wheels, the pose since the scan and the next
  // command's turn move the body a few millimetres off the arc the guard
  // checked, and only at a crawl are those millimetres few (0: off).
  double side_margin_m = 0.03;
  double creep_speed_mps = 0.1;
  double max_decel_mps2 = 0.5;     // braking the guard may count on
  // How long the robot keeps its speed after a command before it brakes: the
  // control period, the base driver and the drives. An intel mission touched
  // a wall at its side while the guard's commands went 0.38 -> 0.14 -> 0 m/s
  // in 0.4 s and the robot, 0.18 m/s a tenth of a second after the zero, went
  // on into it (simulated time at x10, where a loaded machine's few ms of
  // delay are tens of ms).
  double latency_s = 0.2;
  // The forward speed the robot may have when the guard starts: the explorer
  // sets its top speed. A restarted explorer does not know whether the base
  // still drives its predecessor's last command (the base driver keeps it
  // for its cmd_timeout_ms), so it assumes the worst until braking at
  // max_decel_mps2 would have stopped the robot.
  double start_speed_mps = 0.0;
};

// How the guard reads a scan. A wall does not end or turn where its returns
// do: the laser samples a wall seen at a grazing angle some millimetres apart
// along it (0.5 deg at 0.3 m and 20 deg: 7.5 mm), and each return is a
// centimetre off in range, which at a grazing angle is along the wall. A
// robot turning round a door's jamb passes its end tangentially, and a
// generated floor with 0.70-0.75 m doors had it touch the jamb 3 mm deep
// (docs/exploration.md, "Scan guard"); a convex corner between two returns
// lies in front of both, up to a beam spacing along the flatter wall.
struct GuardScanOptions {
  // How far beyond the last return of a wall its end (or a corner) may lie:
  // one beam spacing at a grazing angle and twice the LMS1xx's 12 mm range
  // noise. The guard checks points along the wall up to here (0: the
  // returns only).
  double wall_end_reach_m = 0.03;
  double wall_end_step_m = 0.005;  // spacing of those points
  // A return ends a wall where its neighbouring beam has no return or one
  // this much farther (a step in depth, not the noise between two returns
  // of one wall: 4 sigma of it).
  double wall_end_jump_m = 0.07;
  // A wall's direction: the principal axis of its returns within this of
  // the one it is taken at (fewer than 3: at an end, across the beam toward
  // the gap; at a corner, none).
  double wall_fit_m = 0.10;
  // A beam without a return that runs into a wall of the planning map within
  // this reads that wall (ranges_with_map_walls): a laser blind in a sector
  // (part of its window covered) sees nothing there, and the guard, which
  // acts on returns, would let the robot drive into a wall the map holds. 0: off.
  double map_walls_m = 2.0;
};

// The scan's ranges with each beam without a return (as guard_points reads
// them) that runs into an obstacle edge of `map` (a planning map, free
// interior on the left of its edges) within reach_m reading the distance to
// that edge; `sensor_in_map` is the sensor's pose in the map's frame.
// `filled`, if given, counts those beams. Returns fill in nothing. Built on
// mapping::known_walls / no_return_extents, as the mapper stops such beams.
// `blind`, if given, observes the scan against those walls (which beams of
// the laser are blind: mapping/blind_beams.hpp).
std::vector<float> ranges_with_map_walls(std::span<const float> ranges, double angle_min, double angle_increment,
                                         double range_min, double range_max, const geometry::Pose2& sensor_in_map,
                                         const mapping::TypedMultiPolygon& map, double reach_m, int* filled = nullptr,
                                         mapping::BlindBeams* blind = nullptr);

// The points the guard checks, in the robot's frame: every return of the
// scan (beam i at angle_min + i * angle_increment in the sensor's frame;
// readings that are not finite, below range_min or at/beyond range_max are
// no return), then points along each wall past its returns, up to
// wall_end_reach_m: beyond a wall's end (a neighbour without a return or a
// step deeper), and on to a convex corner between two returns of one wall
// (where the two walls' lines meet in front of the line between the returns;
// with one wall's direction only, where its line crosses the other beam's
// ray in front of that beam's return). Beyond the scan's first and last
// beams nothing is known: no wall ends there. Noise-free, the
// free distance read from these points is never more than what the walls
// allow (GuardPoints.TheBodyTurningRoundAJambsEnd...).
std::vector<mapping::Point> guard_points(std::span<const float> ranges, double angle_min, double angle_increment,
                                         double range_min, double range_max, const geometry::Pose2& sensor_on_robot,
                                         const GuardScanOptions& options);

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

// The guard between the follower and the wheels: it keeps a model of the
// forward speed the robot may still have (the commands it let through,
// braked no faster than max_decel_mps2), because a robot does not turn onto a
// new arc at the speed it is told but at the speed it has.
//
// A forward command keeps its curvature (the follower's path) at a speed from
// which the robot can brake on that arc margin_m short of the first return,
// counting what it may have driven since the scan as used up, and at most
// creep_speed_mps while a return lies within side_margin_m of the band the
// body sweeps. A new arc the robot cannot brake on from the speed it may still
// have is refused: the command is a stop, on which the drives brake both
// wheels alike, on the arc the robot is driving (the one let through before,
// checked when it was). Blocked with the robot stopped, it turns on the spot
// at the commanded rate: a disk turning in place sweeps nothing new, one
// turning while it rolls swings its side off the arc toward the turn (fr079,
// simulated: a straight run 1 mm past a corner, then a turn toward it at
// 0.4 m/s). For the same reason a turn on the spot the follower asks for is
// a stop until the robot may have stopped. Commands that drive backward
// pass unchanged.
// Pure: points and time steps in, command out; no clock, no I/O.
class ScanGuard {
 public:
  explicit ScanGuard(ScanGuardOptions options = {})
      : options_(options), speed_mps_(std::max(0.0, options.start_speed_mps)) {}

  // The command to send step_s after the previous one, on returns (robot
  // frame) taken since_scan_s ago.
  GuardedCommand command(std::span<const mapping::Point> points_robot_frame, double v_mps, double omega_radps,
                         double since_scan_s, double step_s);
  // A command sent without the guard (no scan yet, guard off): the speed
  // model follows it too.
  void sent(double v_mps, double step_s);
  // The forward speed the robot may still have (m/s).
  double speed_mps() const { return speed_mps_; }

 private:
  // The speed the robot may have step_s after the last command, braking.
  double braked_speed(double step_s) const;

  ScanGuardOptions options_;
  double speed_mps_ = 0.0;
};

}  // namespace pex::planning
