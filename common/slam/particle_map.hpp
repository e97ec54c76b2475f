#pragma once
// The seam between the filter and what each particle matches its scans
// against. The filter only needs: score a pose, insert a scan, copy the map for
// a resampled child. CowGridMap (cow_grid_map.hpp) is GMapping's choice; a map
// matching against the particle's own polygon map would implement the same.
#include <cstddef>
#include <memory>

#include "geometry/pose2.hpp"
#include "slam/scan.hpp"

namespace pex::slam {

using geometry::Pose2;

struct PoseEvaluation {
  double score = 0.0;           // matching score: larger is better, >= 0
  double log_likelihood = 0.0;  // log p(scan | pose, map), up to a constant
  std::size_t matched_beams = 0;
};

class ParticleMap {
 public:
  virtual ~ParticleMap() = default;
  // A copy whose later changes do not show in this map (nor the reverse);
  // implementations share unchanged structure.
  virtual std::unique_ptr<ParticleMap> clone() const = 0;
  // Integrates a scan taken from `robot_pose`. Returns how many of its end
  // points the map left out (a map of bounded extent: beyond it).
  virtual std::size_t insert(const Pose2& robot_pose, const ScanPoints& scan) = 0;
  // Score and likelihood of `scan` taken from `robot_pose`. Must be a pure
  // function of the map, the pose and the scan.
  virtual PoseEvaluation evaluate(const Pose2& robot_pose, const ScanPoints& scan) const = 0;
  // evaluate(...).log_likelihood, equal to it bit for bit; a map may compute
  // it alone for less (the proposal's 27 samples need nothing else).
  virtual double log_likelihood(const Pose2& robot_pose, const ScanPoints& scan) const {
    return evaluate(robot_pose, scan).log_likelihood;
  }
  // Bytes of storage this map references (shared parts counted fully).
  virtual std::size_t referenced_bytes() const = 0;
};

}  // namespace pex::slam
