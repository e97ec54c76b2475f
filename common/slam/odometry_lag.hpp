#pragma once
// Estimates how far a log's or a robot's odometry time stamps run ahead of its
// scans' (the "lead"), from the scan matcher's own results. Between two filter
// updates the matched heading change is what the robot really turned between
// the two scans; the odometry's heading change between the same times shifted
// by a candidate lead L matches it best at the true lead. The difference only
// shows where the turn rate changes between updates (a constant rate turns as
// much over any shifted interval), so the evidence gathers over a run: one
// robust squared residual per candidate is summed over every update, and the
// lead is the minimum of that curve (refined by a parabola through its
// neighbours). Matching, not odometry, sees the truth here because the scan
// likelihood is far sharper in heading than the motion prior.
//
// Why it matters (FR079, docs/slam.md): stamps off by 0.1 s put every
// update's odometry guess a few degrees off while turning, and every scan
// between updates (carried forward by odometry) too.
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "archive/byte_archive.hpp"
#include "geometry/pose2.hpp"

namespace pex::slam {

using geometry::Pose2;

struct OdometryLagOptions {
  double max_lead_s = 0.3;   // candidates from -max_lead_s to +max_lead_s ...
  double step_s = 0.01;      // ... this far apart
  // A residual counts at most this much (rad): a failed match or a best
  // particle switching lineage is not evidence about the clocks.
  double outlier_rad = 0.1;
  // The estimate is used once this many updates gave evidence.
  int min_updates = 50;
  // An estimate smaller than this (s) is taken as 0: pairing a scan with its
  // own reading (laser-embedded odometry) is exact, and an interpolation a few
  // ms off it only adds the jitter of logs whose stamps run backwards (Intel).
  double min_lead_s = 0.02;
};

class OdometryLagEstimator {
 public:
  explicit OdometryLagEstimator(const OdometryLagOptions& options = {});

  // One filter update's evidence: the matched heading change between the scans
  // at from_utime and to_utime, and the odometry pose at any time (nullopt where
  // it is not known; the update then gives no evidence).
  void add(std::int64_t from_utime, std::int64_t to_utime, double matched_turn_rad,
           const std::function<std::optional<Pose2>(std::int64_t)>& odometry_at);

  bool ready() const { return updates_ >= options_.min_updates; }
  int updates() const { return updates_; }
  // The estimated lead (us); 0 before ready().
  std::int64_t lead_us() const { return lead_us_; }

  // Sealed with the odometry pairing's checkpoint.
  void write(archive::ByteWriter& out) const;
  // Throws archive::ArchiveError when the saved candidates are not this one's.
  void read(archive::ByteReader& in);

 private:
  double candidate_s(std::size_t k) const;
  void estimate();

  OdometryLagOptions options_;
  std::vector<double> cost_;  // summed robust squared residual per candidate
  int updates_ = 0;
  std::int64_t lead_us_ = 0;
};

}  // namespace pex::slam
