#pragma once
// How well a scan pins the robot's position, and in which direction it does
// not. A scan of a featureless corridor only sees walls whose normals cross
// the corridor: along it, matching has nothing to hold (any shift scores the
// same but for the map's own sparse end points, which pull the scan back to
// where the map was seen from), so a matched pose wanders along the corridor
// by centimetres per update and the map bends (docs/slam.md, worlds/loop). In
// such a direction the odometry is the better estimate: the filter takes the
// match across the corridor and the prediction along it (the degeneracy-aware
// correction of Zhang, Kaess, Singh, "On degeneracy of optimization-based
// state estimation problems", ICRA 2016, with the scan's own geometry as the
// constraint).
//
// Each end point's local geometry (the end points of its neighbouring beams
// within a radius) is a line (its normal constrains one direction), a corner
// or clutter (both directions), or unknown (too few neighbours: nothing). The
// information is the sum over end points of n n^T (lines) or I (the others),
// in the robot's frame, in "beams' worth".
#include <Eigen/Core>

#include "slam/scan.hpp"

namespace pex::slam {

struct ScanConstraintOptions {
  // Off: GMapping's filter as published (every particle takes its match);
  // config/slam.toml turns it on for the simulated base.
  bool enabled = false;
  int neighbours = 3;                 // beams on each side looked at for an end point's geometry
  double neighbour_radius_m = 0.3;    // neighbours farther from the end point are not its surface
  // A line: the smaller scatter eigenvalue at most this fraction of the
  // larger, or at most range_noise_m squared (the laser's noise scatters a
  // wall's end points across it by that much).
  double line_flatness = 0.05;
  double range_noise_m = 0.03;
  // A direction with less information than this many end points facing it
  // squarely is not constrained by the scan.
  double min_information_beams = 12.0;
};

struct ScanConstraint {
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();  // robot frame, beams' worth
  int line_points = 0;
  int corner_points = 0;
  // The projection (robot frame) onto the directions whose information is
  // below min_information_beams: zero when the scan constrains both, v v^T
  // for a corridor along v, the identity when it constrains neither.
  Eigen::Matrix2d unconstrained = Eigen::Matrix2d::Zero();
  bool degenerate() const { return !unconstrained.isZero(); }
};

ScanConstraint scan_constraint(const ScanPoints& scan, const ScanConstraintOptions& options);

}  // namespace pex::slam
