#include "planning/path_follower.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "planning/cspace.hpp"

namespace pex::planning {
namespace {

struct SimRun {
  bool reached = false;
  int steps = 0;
  double max_cross_track_m = 0.0;
  double max_speed_mps = 0.0;
  double max_abs_omega_radps = 0.0;
  double max_accel_mps2 = 0.0;
  double max_angular_accel_radps2 = 0.0;
  double min_speed_while_far_mps = 1e9;  // speed when far from the goal and not turning
  Pose2 final_pose;
};

double distance_to_path(const Point& p, const std::vector<Point>& path) {
  double best = 1e300;
  for (std::size_t i = 1; i < path.size(); ++i)
    best = std::min(best, distance(p, closest_point_on_segment(p, path[i - 1], path[i])));
  return best;
}

// A perfect unicycle integrated at 50 Hz for at most 120 s of simulated time.
SimRun simulate(const std::vector<Point>& path, Pose2 pose, const FollowerOptions& options) {
  PathFollower follower(options);
  follower.set_path(path);
  SimRun run;
  const double dt = 0.02;
  VelocityCommand previous;
  for (int i = 0; i < 6000; ++i) {
    const VelocityCommand c = follower.update(pose, dt);
    if (follower.goal_reached()) {  // the stop from creeping speed is the one allowed jump
      EXPECT_LE(previous.v_mps, 2.0 * options.min_speed_mps);
      run.reached = true;
      run.steps = i;
      break;
    }
    run.max_speed_mps = std::max(run.max_speed_mps, std::abs(c.v_mps));
    run.max_abs_omega_radps = std::max(run.max_abs_omega_radps, std::abs(c.omega_radps));
    run.max_accel_mps2 = std::max(run.max_accel_mps2, std::abs(c.v_mps - previous.v_mps) / dt);
    run.max_angular_accel_radps2 =
        std::max(run.max_angular_accel_radps2, std::abs(c.omega_radps - previous.omega_radps) / dt);
    previous = c;
    const bool far = distance(Point(pose.x_m, pose.y_m), path.back()) > 1.5;
    if (far && !follower.turning_in_place() && i > 100) run.min_speed_while_far_mps = std::min(run.min_speed_while_far_mps, c.v_mps);
    pose.x_m += c.v_mps * std::cos(pose.theta_rad) * dt;
    pose.y_m += c.v_mps * std::sin(pose.theta_rad) * dt;
    pose.theta_rad += c.omega_radps * dt;
    run.max_cross_track_m = std::max(run.max_cross_track_m, distance_to_path(Point(pose.x_m, pose.y_m), path));
  }
  run.final_pose = pose;
  return run;
}

void expect_within_limits(const SimRun& run, const FollowerOptions& o) {
  EXPECT_LE(run.max_speed_mps, o.max_speed_mps + 1e-12);
  EXPECT_LE(run.max_abs_omega_radps, o.max_omega_radps + 1e-12);
  EXPECT_LE(run.max_accel_mps2, o.max_accel_mps2 + 1e-9);
  EXPECT_LE(run.max_angular_accel_radps2, o.max_angular_accel_radps2 + 1e-9);
}

TEST(WayBack, TheTrailReversedAsFarAsAsked) {
  const std::vector<Point> trail{Point(0, 0), Point(1, 0), Point(2, 0), Point(2, 1), Point(2, 2)};
  const auto all = way_back(trail, 100.0);
  ASSERT_EQ(all.size(), 5u);
  EXPECT_DOUBLE_EQ(all.front().y(), 2.0);  // from where the robot is
  EXPECT_DOUBLE_EQ(all.back().x(), 0.0);   // to where it was first
  // 2.5 m: the point that reaches it is the last (3 m along).
  const auto part = way_back(trail, 2.5);
  ASSERT_EQ(part.size(), 4u);
  EXPECT_DOUBLE_EQ(part.back().x(), 1.0);
  EXPECT_TRUE(way_back({Point(1, 1)}, 10.0).empty());
}

TEST(PathFollower, ConvergesOnAStraightPathFromAnOffset) {
  FollowerOptions o;
  const std::vector<Point> path{Point(0, 0), Point(8, 0)};
  const SimRun run = simulate(path, Pose2{0.0, 0.3, 0.2}, o);
  ASSERT_TRUE(run.reached);
  EXPECT_LE(distance(Point(run.final_pose.x_m, run.final_pose.y_m), path.back()), o.goal_tolerance_m);
  EXPECT_LT(run.max_cross_track_m, 0.4);
  expect_within_limits(run, o);
  // It drives at full speed in the middle of the path (not crawling).
  EXPECT_GT(run.max_speed_mps, 0.9 * o.max_speed_mps);
}

TEST(PathFollower, TurnsInPlaceThenFollowsAnLShapedPath) {
  FollowerOptions o;
  const std::vector<Point> path{Point(0, 0), Point(5, 0), Point(5, 5)};
  // Facing away from the path: it must turn on the spot first.
  const SimRun run = simulate(path, Pose2{0.0, 0.0, 3.0}, o);
  ASSERT_TRUE(run.reached);
  EXPECT_LE(distance(Point(run.final_pose.x_m, run.final_pose.y_m), path.back()), o.goal_tolerance_m);
  // The corner is cut by no more than the corner tolerance (and a little
  // overshoot of the turn on the spot), far less than the look-ahead.
  EXPECT_LT(run.max_cross_track_m, o.corner_tolerance_m + 0.05);
  expect_within_limits(run, o);
  EXPECT_GT(run.min_speed_while_far_mps, 0.0);
}

TEST(PathFollower, StopsAtTheGoalAndWithoutAPath) {
  PathFollower follower;
  EXPECT_EQ(follower.update(Pose2{0, 0, 0}, 0.1).v_mps, 0.0);  // no path
  follower.set_path({Point(0, 0), Point(0.1, 0)});
  const auto c = follower.update(Pose2{0.05, 0, 0}, 0.1);  // already within tolerance
  EXPECT_TRUE(follower.goal_reached());
  EXPECT_EQ(c.v_mps, 0.0);
  EXPECT_EQ(c.omega_radps, 0.0);
  // NaN pose: zero command, no crash.
  follower.set_path({Point(0, 0), Point(5, 0)});
  const auto n = follower.update(Pose2{std::nan(""), 0, 0}, 0.1);
  EXPECT_EQ(n.v_mps, 0.0);
}

TEST(PathFollower, SlowsDownBeforeTheGoal) {
  FollowerOptions o;
  o.max_speed_mps = 1.0;
  PathFollower follower(o);
  follower.set_path({Point(0, 0), Point(10, 0)});
  Pose2 pose{0, 0, 0};
  double v_far = 0.0;
  for (int i = 0; i < 50; ++i) v_far = follower.update(pose, 0.1).v_mps;  // accelerate in place
  pose.x_m = 9.7;  // 0.3 m before the end
  double v_near = v_far;
  for (int i = 0; i < 20; ++i) v_near = follower.update(pose, 0.1).v_mps;
  EXPECT_NEAR(v_far, o.max_speed_mps, 1e-12);
  EXPECT_LT(v_near, 0.5 * v_far);
  // The braking profile: it can still stop within the distance left.
  EXPECT_LE(v_near, std::sqrt(2.0 * o.max_accel_mps2 * (0.3 - o.goal_tolerance_m)) + 1e-9);
  EXPECT_GE(v_near, o.min_speed_mps - 1e-12);
}

}  // namespace
}  // namespace pex::planning
