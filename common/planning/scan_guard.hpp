#pragma once
// The last line of defence against driving into a wall: the live laser scan,
// in the robot's own frame, bounds the forward speed so that the robot can
// brake before its body touches anything the laser sees ahead. The planner
// keeps paths clear of the *map's* walls, but the map and the pose come from
// SLAM, which can be a decimetre or more off; the scan cannot (intel missions
// touched walls 2-4 times on plans with the full clearance margin, SLAM 0.1-0.4 m
// off the truth). Pure: points in, speed limit out; no clock, no I/O.
#include <span>

#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct ScanGuardOptions {
  double body_radius_m = 0.25;     // the robot's disk itself, no margin
  double margin_m = 0.03;          // kept between the body and a return when stopped
  double max_decel_mps2 = 0.5;     // braking the guard may count on
};

// The distance the robot (a disk of body_radius_m centred at the origin,
// heading along +x) can drive straight forward before it touches one of the
// points (robot frame); +infinity when nothing is in its way, 0 when it
// touches already.
double free_distance_ahead(std::span<const mapping::Point> points_robot_frame, double body_radius_m);

// The largest forward speed from which the robot stops margin_m short of the
// first point in its way: sqrt(2 a (d - margin)), 0 within the margin.
double max_safe_speed(double free_distance_m, const ScanGuardOptions& options);

}  // namespace pex::planning
