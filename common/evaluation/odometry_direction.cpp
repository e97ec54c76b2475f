#include "evaluation/odometry_direction.hpp"

#include <cmath>
#include <optional>
#include <vector>

namespace pex::evaluation {
namespace {

using geometry::Pose2;

Pose2 reversed_translation(const Pose2& step) { return {-step.x_m, -step.y_m, step.theta_rad}; }

}  // namespace

OdometryDirectionResult correct_odometry_direction(CarmenLog& log) {
  OdometryDirectionResult result;
  std::vector<CarmenOdometry>& odom = log.odometry;
  if (odom.size() < 2) return result;

  // reversed[i]: the step from ODOM line i-1 to line i moves forward while its
  // speed is negative.
  std::vector<bool> reversed(odom.size(), false);
  std::optional<std::size_t> first_reversed;
  for (std::size_t i = 1; i < odom.size(); ++i) {
    const Pose2 step = geometry::relative(odom[i - 1].pose, odom[i].pose);
    if (odom[i - 1].tv_mps + odom[i].tv_mps < 0.0 && step.x_m > 0.0) {
      reversed[i] = true;
      ++result.reversed_steps;
      if (!first_reversed) first_reversed = i;
    }
  }
  if (!first_reversed) return result;

  // The ODOM lines' poses, rebuilt from the first reversed step on.
  std::vector<Pose2> original(odom.size());
  for (std::size_t i = 0; i < odom.size(); ++i) original[i] = odom[i].pose;
  for (std::size_t i = *first_reversed; i < odom.size(); ++i) {
    const Pose2 step = geometry::relative(original[i - 1], original[i]);
    odom[i].pose = geometry::compose(odom[i - 1].pose, reversed[i] ? reversed_translation(step) : step);
  }

  // Each laser line's odometry at its offset from the ODOM line nearest in time
  // among the two around it in file order.
  std::vector<std::optional<std::size_t>> next_odom(log.order.size());
  for (std::size_t k = log.order.size(); k-- > 1;)
    next_odom[k - 1] = log.order[k].is_laser ? next_odom[k] : std::optional<std::size_t>(log.order[k].index);
  std::optional<std::size_t> previous_odom;
  for (std::size_t k = 0; k < log.order.size(); ++k) {
    const CarmenLog::Entry& entry = log.order[k];
    if (!entry.is_laser) {
      previous_odom = entry.index;
      continue;
    }
    CarmenLaser& laser = log.lasers[entry.index];
    const std::optional<std::size_t> next = next_odom[k];
    auto distance = [&](std::size_t i) { return std::abs(odom[i].timestamp_s - laser.timestamp_s); };
    std::size_t j = 0;
    if (previous_odom && next)
      j = distance(*next) < distance(*previous_odom) ? *next : *previous_odom;
    else if (previous_odom || next)
      j = previous_odom ? *previous_odom : *next;
    else
      continue;
    Pose2 offset = geometry::relative(original[j], laser.odometry);
    // The step the laser pose lies on: ahead of line j (j -> j+1) or behind it.
    const std::size_t on_step = offset.x_m >= 0.0 ? j + 1 : j;
    const bool on_reversed = on_step >= 1 && on_step < odom.size() && reversed[on_step];
    if (j < *first_reversed && on_step < *first_reversed) continue;  // nothing before it changed
    if (on_reversed) offset = reversed_translation(offset);
    const Pose2 mounting = geometry::relative(laser.odometry, laser.laser_pose);
    laser.odometry = geometry::compose(odom[j].pose, offset);
    laser.laser_pose = geometry::compose(laser.odometry, mounting);
    ++result.changed_laser_poses;
  }
  return result;
}

}  // namespace pex::evaluation
