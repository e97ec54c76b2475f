#include "slam/odometry_sync.hpp"

#include <algorithm>
#include <cmath>

#include "archive/byte_archive.hpp"
#include "slam/pose_archive.hpp"

namespace pex::slam {

bool OdometrySync::possible_step(const Reading& from, const Reading& to) const {
  const StepLimits& l = options_.limits;
  const double t_s = std::max(l.min_interval_s, std::abs(static_cast<double>(to.utime - from.utime)) * 1e-6);
  const Pose2 step = relative(from.raw, to.raw);
  return std::hypot(step.x_m, step.y_m) <= l.max_speed_mps * t_s + l.slack_m &&
         std::abs(step.theta_rad) <= l.max_omega_radps * t_s + l.slack_rad;
}

void OdometrySync::reset_frame(const Reading& first_of_new_frame) {
  // The robot did not move while the odometry restarted: the new frame's first
  // reading is where the last accepted one put it.
  frame_ = compose(odometry_.back().second, inverse(first_of_new_frame.raw));
  ++odometry_resets_;
}

void OdometrySync::store(const Reading& reading) {
  if (!odometry_.empty() && reading.utime < odometry_.back().first) ++out_of_order_odometry_;
  newest_odometry_utime_ = odometry_.empty() ? reading.utime : std::max(newest_odometry_utime_, reading.utime);
  odometry_.emplace_back(reading.utime, compose(frame_, reading.raw));
  while (odometry_.size() > options_.history) odometry_.pop_front();
  last_accepted_ = reading;
}

bool OdometrySync::add_odometry(std::int64_t utime, const Pose2& pose, double heading_variance_rad2) {
  why_.clear();
  const StepLimits& l = options_.limits;
  if (!is_finite(pose) || std::abs(pose.x_m) > l.max_abs_coordinate_m ||
      std::abs(pose.y_m) > l.max_abs_coordinate_m || std::abs(pose.theta_rad) > l.max_abs_heading_rad) {
    ++refused_odometry_;
    why_ = "odometry pose is not finite or not on this planet (|x|, |y| at most " +
           std::to_string(l.max_abs_coordinate_m) + " m, |theta| at most " + std::to_string(l.max_abs_heading_rad) +
           " rad)";
    return false;
  }
  const Reading reading{utime, pose, heading_variance_rad2};
  if (l.enabled && last_accepted_ && std::isfinite(heading_variance_rad2) &&
      std::isfinite(last_accepted_->heading_variance_rad2) &&
      heading_variance_rad2 < last_accepted_->heading_variance_rad2) {
    held_.reset();
    reset_frame(reading);
    store(reading);
    return true;
  }
  if (!l.enabled || !last_accepted_ || possible_step(*last_accepted_, reading)) {
    held_.reset();  // whatever was held was an outlier
    store(reading);
    return true;
  }
  if (held_ && possible_step(*held_, reading)) {
    // Two readings agree on a new frame: the odometry was reset. The held one
    // is where the robot was last seen (it did not move while the odometry
    // restarted); the estimate stays where it was.
    reset_frame(*held_);
    store(*held_);
    held_.reset();
    store(reading);
    return true;
  }
  ++impossible_steps_;
  const Pose2 step = relative(last_accepted_->raw, pose);
  why_ = "odometry step of " + std::to_string(std::hypot(step.x_m, step.y_m)) + " m, " +
         std::to_string(std::abs(step.theta_rad)) + " rad in " +
         std::to_string(std::abs(static_cast<double>(utime - last_accepted_->utime)) * 1e-6) +
         " s is not possible; held (a next reading that agrees with it makes it an odometry reset)";
  held_ = reading;
  return false;
}

std::optional<Pose2> OdometrySync::newest_pose() const {
  if (odometry_.empty()) return std::nullopt;
  return odometry_.back().second;
}

bool OdometrySync::add_scan(RangeScan scan) {
  if (odometry_.empty()) {
    ++dropped_scans_;
    return false;
  }
  scans_.push_back(std::move(scan));
  return true;
}

std::optional<Pose2> OdometrySync::odometry_at(std::int64_t utime) const {
  if (odometry_.empty()) return std::nullopt;
  // Newest first: the reading of exactly this time, else the newest consecutive
  // pair (in arrival order) whose times enclose it.
  for (auto it = odometry_.rbegin(); it != odometry_.rend(); ++it)
    if (it->first == utime) return it->second;
  for (std::size_t i = odometry_.size() - 1; i > 0; --i) {
    const auto& before = odometry_[i - 1];
    const auto& after = odometry_[i];
    if (before.first < utime && utime < after.first) {
      const double f = static_cast<double>(utime - before.first) /
                       static_cast<double>(after.first - before.first);
      const Pose2 step = relative(before.second, after.second);
      return compose(before.second, {f * step.x_m, f * step.y_m, f * step.theta_rad});
    }
  }
  return std::nullopt;
}

Pose2 OdometrySync::pose_at(std::int64_t utime) const {
  if (const std::optional<Pose2> pose = odometry_at(utime)) return *pose;
  // Before every kept reading (a lead reaching back before the first one):
  // the oldest; else (a time after all, or stamps that ran backwards) the
  // newest, as always.
  const bool before_all = std::all_of(odometry_.begin(), odometry_.end(),
                                      [utime](const auto& reading) { return utime < reading.first; });
  return before_all ? odometry_.front().second : odometry_.back().second;
}

std::int64_t OdometrySync::lead_us() const {
  return options_.estimate_lead && lag_.ready() ? lag_.lead_us() : options_.odometry_lead_us;
}

void OdometrySync::observe_update(std::int64_t scan_utime, std::optional<double> matched_turn_rad) {
  if (options_.estimate_lead && last_update_utime_ && matched_turn_rad)
    pending_turns_.push_back({*last_update_utime_, scan_utime, *matched_turn_rad});
  last_update_utime_ = scan_utime;
  constexpr std::size_t kMaxPending = 16;  // odometry that stopped coming: the oldest evidence goes
  while (pending_turns_.size() > kMaxPending) pending_turns_.pop_front();
  const auto reach_us = static_cast<std::int64_t>(std::llround(options_.lag.max_lead_s * 1e6));
  while (!pending_turns_.empty() && pending_turns_.front().to_utime + reach_us <= newest_odometry_utime_) {
    const PendingTurn& t = pending_turns_.front();
    lag_.add(t.from_utime, t.to_utime, t.turn_rad, [this](std::int64_t utime) { return odometry_at(utime); });
    pending_turns_.pop_front();
  }
}

PairedScan OdometrySync::pair_front(std::int64_t wanted_utime) {
  PairedScan paired{std::move(scans_.front()), pose_at(wanted_utime)};
  scans_.pop_front();
  paired.odometry_stale = wanted_utime - newest_odometry_utime_ > options_.max_odometry_age_us;
  if (paired.odometry_stale) ++stale_pairings_;
  return paired;
}

std::vector<PairedScan> OdometrySync::take_ready() {
  std::vector<PairedScan> ready;
  while (!scans_.empty()) {
    const RangeScan& scan = scans_.front();
    const std::int64_t wanted = scan.utime - lead_us();
    const bool odometry_caught_up = newest_odometry_utime_ >= wanted;
    const bool waited_too_long = scans_.back().utime - scan.utime > options_.max_wait_us ||
                                 scans_.size() > options_.max_buffered_scans;
    if (!odometry_caught_up && !waited_too_long) break;
    ready.push_back(pair_front(wanted));
  }
  return ready;
}

std::vector<PairedScan> OdometrySync::flush() {
  std::vector<PairedScan> ready;
  while (!scans_.empty()) ready.push_back(pair_front(scans_.front().utime - lead_us()));
  return ready;
}

namespace {
constexpr std::string_view kCheckpointMagic = "PEXODSYN";
constexpr std::uint32_t kCheckpointVersion = 2;  // 2: the odometry lead estimate
}  // namespace

std::string OdometrySync::checkpoint() const {
  archive::ByteWriter out;
  auto put_reading = [&out](const std::optional<Reading>& r) {
    out.put_bool(r.has_value());
    if (!r) return;
    out.put<std::int64_t>(r->utime);
    put_pose(out, r->raw);
    out.put<double>(r->heading_variance_rad2);
  };
  out.put<std::uint64_t>(odometry_.size());
  for (const auto& [utime, pose] : odometry_) {
    out.put<std::int64_t>(utime);
    put_pose(out, pose);
  }
  out.put<std::uint64_t>(scans_.size());
  for (const RangeScan& scan : scans_) {
    out.put<std::int64_t>(scan.utime);
    out.put<double>(scan.angle_min_rad);
    out.put<double>(scan.angle_increment_rad);
    out.put<double>(scan.range_min_m);
    out.put<double>(scan.range_max_m);
    put_pose(out, scan.sensor_pose);
    out.put<std::uint64_t>(scan.ranges_m.size());
    for (const float r : scan.ranges_m) out.put<float>(r);
  }
  out.put<std::int64_t>(newest_odometry_utime_);
  put_reading(last_accepted_);
  put_reading(held_);
  put_pose(out, frame_);
  out.put<std::uint64_t>(dropped_scans_);
  out.put<std::uint64_t>(refused_odometry_);
  out.put<std::uint64_t>(out_of_order_odometry_);
  out.put<std::uint64_t>(impossible_steps_);
  out.put<std::uint64_t>(odometry_resets_);
  out.put_bool(last_update_utime_.has_value());
  out.put<std::int64_t>(last_update_utime_.value_or(0));
  out.put<std::uint64_t>(pending_turns_.size());
  for (const PendingTurn& t : pending_turns_) {
    out.put<std::int64_t>(t.from_utime);
    out.put<std::int64_t>(t.to_utime);
    out.put<double>(t.turn_rad);
  }
  lag_.write(out);
  return archive::seal(kCheckpointMagic, kCheckpointVersion, out.bytes());
}

std::string OdometrySync::restore(std::string_view checkpoint) {
  try {
    const std::string payload = archive::unseal(kCheckpointMagic, kCheckpointVersion, checkpoint);
    archive::ByteReader in(payload);
    auto get_reading = [&in]() -> std::optional<Reading> {
      if (!in.get_bool()) return std::nullopt;
      Reading r;
      r.utime = in.get<std::int64_t>();
      r.raw = get_pose(in);
      r.heading_variance_rad2 = in.get<double>();
      return r;
    };
    OdometrySync restored(options_);  // replaces this one once all was read
    const std::uint64_t readings = in.get_count(sizeof(std::int64_t) + 3 * sizeof(double));
    for (std::uint64_t i = 0; i < readings; ++i) {
      const auto utime = in.get<std::int64_t>();
      restored.odometry_.emplace_back(utime, get_pose(in));
    }
    while (restored.odometry_.size() > options_.history) restored.odometry_.pop_front();
    const std::uint64_t scans = in.get_count(sizeof(std::int64_t) + 7 * sizeof(double) + sizeof(std::uint64_t));
    for (std::uint64_t i = 0; i < scans; ++i) {
      RangeScan scan;
      scan.utime = in.get<std::int64_t>();
      scan.angle_min_rad = in.get<double>();
      scan.angle_increment_rad = in.get<double>();
      scan.range_min_m = in.get<double>();
      scan.range_max_m = in.get<double>();
      scan.sensor_pose = get_pose(in);
      scan.ranges_m.resize(in.get_count(sizeof(float)));
      for (float& r : scan.ranges_m) r = in.get<float>();
      restored.scans_.push_back(std::move(scan));
    }
    restored.newest_odometry_utime_ = in.get<std::int64_t>();
    restored.last_accepted_ = get_reading();
    restored.held_ = get_reading();
    restored.frame_ = get_pose(in);
    restored.dropped_scans_ = in.get<std::uint64_t>();
    restored.refused_odometry_ = in.get<std::uint64_t>();
    restored.out_of_order_odometry_ = in.get<std::uint64_t>();
    restored.impossible_steps_ = in.get<std::uint64_t>();
    restored.odometry_resets_ = in.get<std::uint64_t>();
    const bool has_update = in.get_bool();
    const auto update_utime = in.get<std::int64_t>();
    if (has_update) restored.last_update_utime_ = update_utime;
    const std::uint64_t pending = in.get_count(2 * sizeof(std::int64_t) + sizeof(double));
    for (std::uint64_t i = 0; i < pending; ++i) {
      PendingTurn t{};
      t.from_utime = in.get<std::int64_t>();
      t.to_utime = in.get<std::int64_t>();
      t.turn_rad = in.get<double>();
      restored.pending_turns_.push_back(t);
    }
    restored.lag_.read(in);
    in.expect_end();
    if (!restored.scans_.empty() && restored.odometry_.empty())
      throw archive::ArchiveError("scans wait for odometry but no reading is kept");
    *this = std::move(restored);
    return "";
  } catch (const archive::ArchiveError& e) {
    return e.what();
  }
}

}  // namespace pex::slam
