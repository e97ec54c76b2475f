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
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "slam/scan.hpp"

namespace pex::slam {

struct OdometrySyncOptions {
  std::int64_t max_wait_us = 500'000;
  std::size_t max_buffered_scans = 64;  // beyond this the oldest scan is paired at once
  std::size_t history = 256;            // odometry readings kept for interpolation
};

struct PairedScan {
  RangeScan scan;
  Pose2 odometry;
};

class OdometrySync {
 public:
  explicit OdometrySync(const OdometrySyncOptions& options = {}) : options_(options) {}

  // A non-finite reading is refused (false); one older than the newest is kept
  // and counted (out_of_order_odometry()).
  bool add_odometry(std::int64_t utime, const Pose2& pose);
  // Buffers a scan; scans before the first odometry reading are dropped (false).
  bool add_scan(RangeScan scan);
  // The scans that can be paired now, in arrival order.
  std::vector<PairedScan> take_ready();
  // Pairs every buffered scan with what is known (end of a log).
  std::vector<PairedScan> flush();

  std::size_t dropped_scans() const { return dropped_scans_; }
  std::size_t refused_odometry() const { return refused_odometry_; }
  std::size_t out_of_order_odometry() const { return out_of_order_odometry_; }

 private:
  Pose2 pose_at(std::int64_t utime) const;

  OdometrySyncOptions options_;
  std::deque<std::pair<std::int64_t, Pose2>> odometry_;
  std::deque<RangeScan> scans_;
  std::size_t dropped_scans_ = 0;
  std::size_t refused_odometry_ = 0;
  std::size_t out_of_order_odometry_ = 0;
  std::int64_t newest_odometry_utime_ = 0;
};

}  // namespace pex::slam
