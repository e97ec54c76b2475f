#include "slam_node.hpp"

#include <cmath>
#include <stdexcept>

#include "archive/byte_archive.hpp"

namespace pex::slam_daemon {

SlamNode::SlamNode(const SlamNodeOptions& options, SlamOutputs outputs)
    : options_(options), outputs_(std::move(outputs)), filter_(options.filter), sync_(options.sync) {}

void SlamNode::on_odometry(const odometry_t& msg) {
  const slam::Pose2 pose{msg.x, msg.y, msg.theta};
  if (!geometry::is_finite(pose)) throw std::invalid_argument("odometry pose is not finite");
  // An impossible step is held back (OdometrySync): SLAM does not move on it.
  if (!sync_.add_odometry(msg.utime, pose, msg.covariance[8])) throw std::invalid_argument(sync_.why());
  process(sync_.take_ready());
  if (filter_.initialized() && outputs_.publish_pose) {
    // In the odometry's first frame (a reset odometry is anchored there).
    const slam::Pose2 best = filter_.best_pose(*sync_.newest_pose());
    pose_t out{};
    out.utime = msg.utime;
    out.x = best.x_m;
    out.y = best.y_m;
    out.theta = best.theta_rad;
    outputs_.publish_pose(out);
  }
}

void SlamNode::on_scan(const laser_scan_t& msg) {
  if (msg.nranges < 0 || static_cast<std::size_t>(msg.nranges) != msg.ranges.size())
    throw std::invalid_argument("nranges disagrees with the ranges array");
  if (msg.ranges.size() > options_.max_beams)
    throw std::invalid_argument("scan has " + std::to_string(msg.ranges.size()) + " beams, more than " +
                                std::to_string(options_.max_beams));
  if (!std::isfinite(msg.angle_min) || !std::isfinite(msg.angle_increment) ||
      !std::isfinite(msg.range_max) || !std::isfinite(msg.range_min) || !std::isfinite(msg.sensor_x) ||
      !std::isfinite(msg.sensor_y) || !std::isfinite(msg.sensor_theta))
    throw std::invalid_argument("scan geometry is not finite");
  if (std::hypot(msg.sensor_x, msg.sensor_y) > options_.max_sensor_offset_m)
    throw std::invalid_argument("laser mounted " + std::to_string(std::hypot(msg.sensor_x, msg.sensor_y)) +
                                " m from the robot, more than " + std::to_string(options_.max_sensor_offset_m));
  slam::RangeScan scan;
  scan.utime = msg.utime;
  scan.angle_min_rad = msg.angle_min;
  scan.angle_increment_rad = msg.angle_increment;
  scan.range_min_m = msg.range_min;
  scan.range_max_m = msg.range_max;
  scan.sensor_pose = {msg.sensor_x, msg.sensor_y, msg.sensor_theta};
  scan.ranges_m = msg.ranges;  // NaN / out-of-range readings are "no return" in the filter
  sync_.add_scan(std::move(scan));
  process(sync_.take_ready());
}

void SlamNode::flush() { process(sync_.flush()); }

void SlamNode::process(std::vector<slam::PairedScan> ready) {
  for (const slam::PairedScan& paired : ready) {
    if (paired.odometry_stale) continue;  // no motion prior: an update would put the scan anywhere (counted by sync_)
    const bool updated = filter_.process(paired.scan, paired.odometry);
    if (updated) sync_.observe_update(paired.scan.utime, filter_.best_turn_at_last_update());
    if (options_.record_trajectory) recorder_.record(paired.scan.utime, filter_, paired.odometry);
    ++scans_processed_;
    if (!outputs_.publish_update || !filter_.initialized()) continue;
    const auto period_us = static_cast<std::int64_t>(options_.republish_period_s * 1e6);
    if (updated && epoch_ == 0) epoch_ = paired.scan.utime > 0 ? paired.scan.utime : 1;  // a new lineage
    if (updated) {
      outputs_.publish_update(update_message(paired.scan.utime));
      last_published_scan_utime_ = paired.scan.utime;
    } else if (period_us > 0 && paired.scan.utime - last_published_scan_utime_ >= period_us &&
               filter_.travel_since_update_m() <= options_.republish_max_travel_m &&
               filter_.turn_since_update_rad() <= options_.republish_max_turn_rad) {
      outputs_.publish_update(republish_message(paired.scan.utime));
      last_published_scan_utime_ = paired.scan.utime;
      ++republished_;
    }
  }
}

slam_update_t SlamNode::republish_message(std::int64_t scan_utime) const {
  slam_update_t msg = update_message(scan_utime);
  // Every particle is its own parent: the maps are extended, none copied.
  msg.resampled = false;
  msg.republished = true;
  for (std::size_t i = 0; i < msg.particles.size(); ++i) msg.particles[i].parent = static_cast<std::int32_t>(i);
  return msg;
}

slam_update_t SlamNode::update_message(std::int64_t scan_utime) const {
  slam_update_t msg{};
  msg.utime = scan_utime;
  msg.scan_utime = scan_utime;
  msg.epoch = epoch_;
  msg.generation = filter_.generation();
  msg.resampled = filter_.last_update().resampled;
  msg.best = static_cast<std::int32_t>(filter_.best_index());
  const auto& particles = filter_.particles();
  const std::vector<double> weights = filter_.normalized_weights();
  msg.nparticles = static_cast<std::int32_t>(particles.size());
  msg.particles.resize(particles.size());
  for (std::size_t i = 0; i < particles.size(); ++i) {
    particle_t& p = msg.particles[i];
    p.x = particles[i].pose.x_m;
    p.y = particles[i].pose.y_m;
    p.theta = particles[i].pose.theta_rad;
    p.log_weight = weights[i] > 0.0 ? std::log(weights[i]) : -1e300;
    p.parent = particles[i].parent;
  }
  return msg;
}

std::string SlamNode::trajectory_text() const {
  // Progress between updates weighs a turn as the update gate does (0.5 m or 0.25 rad: 2 m per rad).
  const double linear_per_rad = options_.filter.angular_update_rad > 0.0
                                   ? options_.filter.linear_update_m / options_.filter.angular_update_rad
                                   : 2.0;
  return slam::trajectory_text(recorder_.resolve(filter_, options_.spread_corrections, linear_per_rad));
}

namespace {
constexpr std::string_view kCheckpointMagic = "PEXSLAMN";
constexpr std::uint32_t kCheckpointVersion = 1;
}  // namespace

std::string SlamNode::checkpoint() const {
  archive::ByteWriter out;
  out.put<std::int64_t>(epoch_);
  out.put<std::int64_t>(last_published_scan_utime_);
  out.put<std::int64_t>(scans_processed_);
  out.put<std::int64_t>(republished_);
  out.put_string(filter_.checkpoint());
  out.put_string(sync_.checkpoint());
  return archive::seal(kCheckpointMagic, kCheckpointVersion, out.bytes());
}

std::string SlamNode::restore(std::string_view checkpoint) {
  try {
    const std::string payload = archive::unseal(kCheckpointMagic, kCheckpointVersion, checkpoint);
    archive::ByteReader in(payload);
    const auto epoch = in.get<std::int64_t>();
    const auto last_published_scan_utime = in.get<std::int64_t>();
    const auto scans_processed = in.get<std::int64_t>();
    const auto republished = in.get<std::int64_t>();
    // Both parts are taken up into new ones first: all or nothing.
    slam::ParticleFilter filter(options_.filter);
    if (auto why = filter.restore(in.get_string()); !why.empty()) return "the filter: " + why;
    slam::OdometrySync sync(options_.sync);
    if (auto why = sync.restore(in.get_string()); !why.empty()) return "the odometry pairing: " + why;
    in.expect_end();
    filter_ = std::move(filter);
    sync_ = std::move(sync);
    recorder_ = slam::TrajectoryRecorder{};
    epoch_ = epoch;
    last_published_scan_utime_ = last_published_scan_utime;
    scans_processed_ = scans_processed;
    republished_ = republished;
    return "";
  } catch (const archive::ArchiveError& e) {
    return e.what();
  }
}

}  // namespace pex::slam_daemon
