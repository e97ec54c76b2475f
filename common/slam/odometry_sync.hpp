#pragma once
// Pairs each laser scan with the odometry pose at the scan's time. Scans wait
// until an odometry reading at or after their time has arrived and are then
// paired with the reading of the same time, or the pose interpolated between the
// latest two readings around them; a scan whose odometry does not come within
// `max_wait_us` (scan time) is paired with the newest reading. Driven only by
// the order of the inputs, so a replay pairs exactly as the live run did.
//
// Real logs carry host time stamps that sometimes go backwards (the Intel log's
// IPC time stamps do, by up to 0.6 s, while its order of arrival is right), so
// readings are kept in arrival order and searched from the newest back.
//
// Physically impossible steps. A reading the robot cannot have reached from the
// newest accepted one (farther or more turned than StepLimits allow in the time
// between them) is held back and counted (impossible_steps()): one absurd
// message (x = 1e300) does not move SLAM. When the next reading is possible
// from the held one, the odometry was reset: the new frame is anchored so that
// the held reading is where the robot was last seen, and the estimate does not
// jump (odometry_resets()). A reading whose heading variance is smaller than
// the one before is a reset too, at once: an odometry integrator only ever
// adds to it (kinematics::OdometryIntegrator: P22' = P22 + q), so a smaller one
// is a new integrator (a restarted base driver, counting from (0, 0) again,
// after a gap however long). The other terms may shrink (the shear of the
// motion Jacobian), so they are not used. The speeds in
// the readings are not used: logs (Intel, FR079) carry zeros there while the
// robot moves. Every stored pose is in the first frame.
#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "slam/odometry_lag.hpp"
#include "slam/scan.hpp"

namespace pex::slam {

// What the robot can do, generously: a step beyond it is not a motion.
struct StepLimits {
  bool enabled = true;
  double max_speed_mps = 2.0;
  double max_omega_radps = 4.0;
  double min_interval_s = 0.05;  // time stamps closer than this are taken this far apart (jitter)
  double slack_m = 0.05;         // added to every bound (noise)
  double slack_rad = 0.05;
  double max_abs_coordinate_m = 1e6;  // beyond: refused as not a pose
  // Beyond: refused as not a heading. An odometry that does not wrap its
  // heading stays far below (16 000 turns); past it, cos and sin of the raw
  // value and of its wrap disagree enough that a reset frame anchored on it
  // moves the robot by kilometres (a heading of -7.8e202 rad at x = 131 km put
  // SLAM's grid 36 km away: the fuzz finding of 2026-11-26).
  double max_abs_heading_rad = 1e5;
};

struct OdometrySyncOptions {
  StepLimits limits;
  std::int64_t max_wait_us = 500'000;
  // A scan paired with a reading older than its time by more than this (the
  // odometry stopped or fell behind, and the scan waited max_wait_us) has no
  // motion prior worth the name: it is marked odometry_stale. While turning
  // at 0.7 rad/s, 0.8 s of it put a filter update 32 degrees off, beyond the
  // matcher's reach, and that scan into every particle's map (a simulated
  // mission at x10, where 80 ms of a loaded machine is 0.8 s).
  std::int64_t max_odometry_age_us = 100'000;
  std::size_t max_buffered_scans = 64;  // beyond this the oldest scan is paired at once
  std::size_t history = 256;            // odometry readings kept for interpolation
  // How far the odometry's time stamps run ahead of the scans' (us): a scan
  // stamped t is paired with the odometry stamped t - lead. A logger that
  // stamps odometry when it is read but scans when they were taken (or the
  // reverse) skews the pairing by a fixed lag; while turning, 0.1 s of it is a
  // few degrees of prior the matcher must undo at every update, and as much
  // error in every pose carried forward between updates. Negative: the
  // odometry lags. With estimate_lead this is only the value used until the
  // estimate (OdometryLagEstimator, fed by observe_update) is ready.
  std::int64_t odometry_lead_us = 0;
  bool estimate_lead = false;
  OdometryLagOptions lag;
};

struct PairedScan {
  RangeScan scan;
  Pose2 odometry;
  bool odometry_stale = false;  // see OdometrySyncOptions::max_odometry_age_us
};

class OdometrySync {
 public:
  explicit OdometrySync(const OdometrySyncOptions& options = {}) : options_(options) {}

  // A non-finite reading is refused (false); one older than the newest is kept
  // and counted (out_of_order_odometry()). heading_variance_rad2: the reading's
  // covariance[8] (NaN: unknown). false also when the step is impossible (held,
  // see above); why() says why.
  bool add_odometry(std::int64_t utime, const Pose2& pose, double heading_variance_rad2 = std::nan(""));
  const std::string& why() const { return why_; }
  // The newest accepted reading, in the first frame (nullopt: none yet).
  std::optional<Pose2> newest_pose() const;
  // Buffers a scan; scans before the first odometry reading are dropped (false).
  bool add_scan(RangeScan scan);
  // The scans that can be paired now, in arrival order.
  std::vector<PairedScan> take_ready();
  // Pairs every buffered scan with what is known (end of a log).
  std::vector<PairedScan> flush();

  std::size_t dropped_scans() const { return dropped_scans_; }
  std::size_t refused_odometry() const { return refused_odometry_; }
  std::size_t out_of_order_odometry() const { return out_of_order_odometry_; }
  std::size_t impossible_steps() const { return impossible_steps_; }
  std::size_t odometry_resets() const { return odometry_resets_; }
  std::size_t stale_pairings() const { return stale_pairings_; }

  // A filter update ran on the scan stamped scan_utime, and the best
  // particle's lineage turned matched_turn_rad since the previous update
  // (nullopt: not known): evidence for the odometry lead.
  void observe_update(std::int64_t scan_utime, std::optional<double> matched_turn_rad);
  // The lead (us) the pairing uses now.
  std::int64_t lead_us() const;
  const OdometryLagEstimator& lag_estimator() const { return lag_; }
  // The odometry pose at utime, interpolated between the kept readings that
  // enclose it; nullopt outside them.
  std::optional<Pose2> odometry_at(std::int64_t utime) const;

  // The pairing survives a restart of SLAM with the filter (issue 11): the
  // frame that anchors a reset odometry (without it a SLAM restarted after a
  // base driver restart would jump by the whole reset), the last accepted and
  // the held reading (so an odometry reset during the restart is still seen),
  // the readings kept for interpolation, the scans waiting for odometry and
  // the counters. A sealed archive (archive/byte_archive.hpp).
  std::string checkpoint() const;
  // "" or why it was refused; unchanged then. The options stay this one's.
  std::string restore(std::string_view checkpoint);

 private:
  // The oldest buffered scan with the odometry at wanted_utime, marked stale or not.
  PairedScan pair_front(std::int64_t wanted_utime);
  struct Reading {
    std::int64_t utime;
    Pose2 raw;  // as received (its own frame)
    double heading_variance_rad2;
  };
  Pose2 pose_at(std::int64_t utime) const;
  bool possible_step(const Reading& from, const Reading& to) const;
  void store(const Reading& reading);
  void reset_frame(const Reading& first_of_new_frame);

  OdometrySyncOptions options_;
  std::deque<std::pair<std::int64_t, Pose2>> odometry_;
  std::deque<RangeScan> scans_;
  std::size_t dropped_scans_ = 0;
  std::size_t refused_odometry_ = 0;
  std::size_t out_of_order_odometry_ = 0;
  std::int64_t newest_odometry_utime_ = 0;
  std::optional<Reading> last_accepted_;
  std::optional<Reading> held_;   // an impossible step, kept to tell an outlier from a reset
  Pose2 frame_;                   // raw -> first frame
  std::size_t impossible_steps_ = 0;
  std::size_t odometry_resets_ = 0;
  std::size_t stale_pairings_ = 0;
  std::string why_;
  OdometryLagEstimator lag_{options_.lag};
  std::optional<std::int64_t> last_update_utime_;
  // Turns between updates waiting until the odometry reaches max_lead_s past
  // them (a negative candidate lead looks into the odometry after the scan).
  struct PendingTurn {
    std::int64_t from_utime;
    std::int64_t to_utime;
    double turn_rad;
  };
  std::deque<PendingTurn> pending_turns_;
};

}  // namespace pex::slam
