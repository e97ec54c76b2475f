#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "slam/cow_grid_map.hpp"
#include "slam/motion_model.hpp"
#include "slam/odometry_sync.hpp"
#include "slam/particle_filter.hpp"
#include "slam/scan_matcher.hpp"
#include "slam/trajectory_recorder.hpp"

namespace pex::slam {
namespace {

// A synthetic room: outer walls, an inner pillar and a diagonal wall, so a scan
// pins down x, y and heading.
struct Segment {
  double x0, y0, x1, y1;
};
const std::vector<Segment>& room() {
  static const std::vector<Segment> walls = {
      {-6, -4, 6, -4}, {6, -4, 6, 4},  {6, 4, -6, 4},     {-6, 4, -6, -4},  // outer
      {1, 1, 2, 1},    {2, 1, 2, 2},   {2, 2, 1, 2},      {1, 2, 1, 1},     // pillar
      {-4, -4, -6, -1}, {3, -4, 6, -2}};                                     // diagonals
  return walls;
}

double cast(double ox, double oy, double angle) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& s : room()) {
    const double ex = s.x1 - s.x0, ey = s.y1 - s.y0;
    const double den = dx * ey - dy * ex;
    if (std::abs(den) < 1e-12) continue;
    const double t = ((s.x0 - ox) * ey - (s.y0 - oy) * ex) / den;
    const double u = ((s.x0 - ox) * dy - (s.y0 - oy) * dx) / den;
    if (t > 0 && u >= 0 && u <= 1) best = std::min(best, t);
  }
  return best;
}

RangeScan scan_from(const Pose2& pose, std::int64_t utime = 0, int beams = 361) {
  RangeScan scan;
  scan.utime = utime;
  scan.angle_min_rad = -std::numbers::pi / 2;
  scan.angle_increment_rad = std::numbers::pi / (beams - 1);
  scan.range_min_m = 0.05;
  scan.range_max_m = 30.0;
  for (int i = 0; i < beams; ++i)
    scan.ranges_m.push_back(static_cast<float>(
        cast(pose.x_m, pose.y_m, pose.theta_rad + scan.angle_min_rad + i * scan.angle_increment_rad)));
  return scan;
}

TEST(MotionModel, SampleStatisticsFollowTheNoiseParameters) {
  MotionModelOptions options;
  std::mt19937_64 rng(7);
  const Pose2 step{1.0, 0.0, 0.0};
  const Pose2 sigma = motion_noise_std(step, options);
  EXPECT_DOUBLE_EQ(sigma.x_m, options.srr);
  EXPECT_DOUBLE_EQ(sigma.y_m, 0.3 * options.srr);
  EXPECT_DOUBLE_EQ(sigma.theta_rad, options.srt);
  constexpr int kN = 20000;
  double sum_x = 0, sum_xx = 0, sum_t = 0, sum_tt = 0;
  for (int i = 0; i < kN; ++i) {
    const Pose2 p = sample_motion({}, step, options, rng);
    sum_x += p.x_m;
    sum_xx += p.x_m * p.x_m;
    sum_t += p.theta_rad;
    sum_tt += p.theta_rad * p.theta_rad;
  }
  const double mean_x = sum_x / kN, mean_t = sum_t / kN;
  EXPECT_NEAR(mean_x, 1.0, 0.005);
  EXPECT_NEAR(mean_t, 0.0, 0.01);
  EXPECT_NEAR(std::sqrt(sum_xx / kN - mean_x * mean_x), options.srr, 0.005);
  EXPECT_NEAR(std::sqrt(sum_tt / kN - mean_t * mean_t), options.srt, 0.01);
  // A pure rotation moves with rotation noise only in theta, str in x/y.
  const Pose2 turn_sigma = motion_noise_std({0.0, 0.0, 1.0}, options);
  EXPECT_DOUBLE_EQ(turn_sigma.theta_rad, options.stt);
  EXPECT_DOUBLE_EQ(turn_sigma.x_m, options.str);
}

TEST(Pose2, ComposeAndRelativeAreInverse) {
  const Pose2 a{1.0, -2.0, 2.5}, b{0.3, 0.7, -3.0};
  const Pose2 r = relative(a, compose(a, b));
  EXPECT_NEAR(r.x_m, b.x_m, 1e-12);
  EXPECT_NEAR(r.y_m, b.y_m, 1e-12);
  EXPECT_NEAR(r.theta_rad, b.theta_rad, 1e-12);
  const Pose2 id = compose(a, inverse(a));
  EXPECT_NEAR(std::hypot(id.x_m, id.y_m), 0.0, 1e-12);
}

TEST(CowGridMap, ClonesShareTilesAndCopyOnWrite) {
  CowGridMap map({});
  const Pose2 pose{0.0, 0.0, 0.0};
  const ScanPoints points = to_scan_points(scan_from(pose), {});
  map.insert(pose, points);
  ASSERT_GT(map.tile_count(), 0u);
  auto copy = map.clone();
  const CowGridMap::Cell* original = map.cell_at(6.0 + 0.01, 0.0);
  ASSERT_NE(original, nullptr);
  const std::uint32_t hits_before = original->hits;
  static_assert(sizeof(CowGridMap::Cell) == 24);
  EXPECT_GT(hits_before, 0u);
  copy->insert(pose, points);
  // The copy's write did not reach the original...
  EXPECT_EQ(map.cell_at(6.0 + 0.01, 0.0)->hits, hits_before);
  // ...and the copy has the doubled hits.
  const auto* copy_grid = dynamic_cast<const CowGridMap*>(copy.get());
  ASSERT_NE(copy_grid, nullptr);
  EXPECT_EQ(copy_grid->cell_at(6.0 + 0.01, 0.0)->hits, 2 * hits_before);
  // A cell no beam reached stays unknown.
  EXPECT_TRUE(map.cell_at(0.0, 0.0) == nullptr || map.cell_at(0.0, 0.0)->hits == 0);
}

TEST(ScanMatcher, RecoversAKnownOffset) {
  // A map from scans at known poses along a short path, as the filter builds it.
  CowGridMap map({});
  for (int i = 0; i < 6; ++i) {
    const Pose2 known{0.2 + 0.1 * i, -0.5 + 0.02 * i, 0.3 + 0.01 * i};
    map.insert(known, to_scan_points(scan_from(known), {}));
  }
  // A scan from a nearby pose, matched from a guess off by 12 cm / 3°.
  const Pose2 moved{0.8, -0.4, 0.35};
  const ScanPoints points = to_scan_points(scan_from(moved), {});
  const Pose2 guess{moved.x_m + 0.08, moved.y_m - 0.09, moved.theta_rad + 0.05};
  const MatchResult match = match_scan(map, points, guess, {});
  EXPECT_NEAR(match.pose.x_m, moved.x_m, 0.015);
  EXPECT_NEAR(match.pose.y_m, moved.y_m, 0.015);
  EXPECT_NEAR(match.pose.theta_rad, moved.theta_rad, 0.01);
  EXPECT_GT(match.evaluation.score, map.evaluate(guess, points).score);
  EXPECT_GT(match.evaluation.log_likelihood, map.evaluate(guess, points).log_likelihood);
}

TEST(CowGridMap, CellsOnAWallLearnTheWallNormal) {
  CowGridMap map({});
  for (int i = 0; i < 10; ++i) {
    const Pose2 known{0.1 * i, 0.013 * i, 0.0};
    map.insert(known, to_scan_points(scan_from(known), {}));
  }
  // The wall x = 6 (seen head-on): the best-filled cell on it has a normal along x.
  const CowGridMap::Cell* best = nullptr;
  for (double y = -1.0; y <= 1.0; y += 0.05) {
    const CowGridMap::Cell* cell = map.cell_at(6.01, y);
    if (cell && (!best || cell->hits > best->hits)) best = cell;
  }
  ASSERT_NE(best, nullptr);
  ASSERT_GE(best->hits, 3u);
  EXPECT_NEAR(std::abs(best->normal_x) / 127.0, 1.0, 0.05);
  EXPECT_NEAR(best->normal_y / 127.0, 0.0, 0.3);
}

TEST(Resampling, SystematicResamplingPicksParentsByWeight) {
  EXPECT_EQ(systematic_resample({0.0, 1.0, 0.0, 0.0}, 0.1), (std::vector<int>{1, 1, 1, 1}));
  EXPECT_EQ(systematic_resample({0.5, 0.0, 0.0, 0.5}, 0.2), (std::vector<int>{0, 0, 3, 3}));
  EXPECT_EQ(systematic_resample({0.25, 0.25, 0.25, 0.25}, 0.1), (std::vector<int>{0, 1, 2, 3}));
}

// Drives the filter along a path in the synthetic room with noisy odometry.
struct Drive {
  std::vector<Pose2> truth;
  std::vector<Pose2> odometry;
};
// A loop of radius 1.5 m around (-2, 0), clear of every wall, with odometry
// that overestimates distance by 5% and drifts in heading.
Drive drive(std::uint64_t seed) {
  Drive d;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Pose2 truth{-2.0, -1.5, 0.0};
  Pose2 odom = truth;
  for (int i = 0; i < 120; ++i) {
    const Pose2 step{0.1, 0.0, 0.1 / 1.5};
    truth = compose(truth, step);
    odom = compose(odom, {step.x_m * (1.05 + 0.02 * noise(rng)), 0.005 * noise(rng),
                          step.theta_rad + 0.01 * noise(rng) + 0.006});
    d.truth.push_back(truth);
    d.odometry.push_back(odom);
  }
  return d;
}

ParticleFilterOptions small_filter(std::uint64_t seed) {
  ParticleFilterOptions options;
  options.particle_count = 10;
  options.seed = seed;
  options.linear_update_m = 0.3;
  return options;
}

TEST(ParticleFilter, ChildrenDescendFromTheirParents) {
  const Drive d = drive(3);
  ParticleFilter filter(small_filter(5));
  int resampled_updates = 0;
  for (std::size_t i = 0; i < d.truth.size(); ++i) {
    std::vector<const TrajectoryNode*> previous;
    for (const Particle& p : filter.particles()) previous.push_back(p.trajectory.get());
    const bool updated = filter.process(scan_from(d.truth[i], static_cast<std::int64_t>(i) * 100000), d.odometry[i]);
    if (!updated || previous.empty()) continue;
    const auto& particles = filter.particles();
    for (std::size_t k = 0; k < particles.size(); ++k) {
      const int parent = particles[k].parent;
      ASSERT_GE(parent, 0);
      ASSERT_LT(static_cast<std::size_t>(parent), previous.size());
      EXPECT_EQ(particles[k].trajectory->parent.get(), previous[static_cast<std::size_t>(parent)]);
      if (!filter.last_update().resampled) {
        EXPECT_EQ(parent, static_cast<int>(k));
      }
    }
    resampled_updates += filter.last_update().resampled;
  }
  EXPECT_GT(filter.generation(), 5);
  (void)resampled_updates;
}

TEST(ParticleFilter, CorrectsOdometryDriftInASyntheticRoom) {
  const Drive d = drive(11);
  ParticleFilter filter(small_filter(5));
  TrajectoryRecorder recorder;
  for (std::size_t i = 0; i < d.truth.size(); ++i) {
    filter.process(scan_from(d.truth[i], static_cast<std::int64_t>(i)), d.odometry[i]);
    recorder.record(static_cast<std::int64_t>(i), filter, d.odometry[i]);
  }
  // Compare relative motion of the estimate and of odometry over the run with the truth.
  const auto poses = recorder.resolve(filter);
  ASSERT_EQ(poses.size(), d.truth.size());
  const Pose2 true_motion = relative(d.truth.front(), d.truth.back());
  const Pose2 est_motion = relative(poses.front().pose, poses.back().pose);
  const Pose2 odo_motion = relative(d.odometry.front(), d.odometry.back());
  const double est_error = std::hypot(est_motion.x_m - true_motion.x_m, est_motion.y_m - true_motion.y_m);
  const double odo_error = std::hypot(odo_motion.x_m - true_motion.x_m, odo_motion.y_m - true_motion.y_m);
  EXPECT_GT(odo_error, 0.3);
  EXPECT_LT(est_error, 0.1);
}

TEST(ParticleFilter, SameSeedSameResultDifferentSeedDifferent) {
  const Drive d = drive(3);
  auto run = [&](std::uint64_t seed) {
    ParticleFilter filter(small_filter(seed));
    for (std::size_t i = 0; i < 60; ++i) filter.process(scan_from(d.truth[i], static_cast<std::int64_t>(i)), d.odometry[i]);
    std::vector<double> state;
    for (const Particle& p : filter.particles()) {
      state.push_back(p.pose.x_m);
      state.push_back(p.pose.y_m);
      state.push_back(p.pose.theta_rad);
      state.push_back(p.log_weight);
    }
    return state;
  };
  EXPECT_EQ(run(42), run(42));  // bit for bit
  EXPECT_NE(run(42), run(43));
}

TEST(ParticleFilter, ScansWithoutReturnsOrBadOdometryAreIgnored) {
  ParticleFilter filter(small_filter(1));
  RangeScan empty = scan_from({}, 0, 90);
  for (float& r : empty.ranges_m) r = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(filter.process(empty, {}));
  EXPECT_FALSE(filter.initialized());
  EXPECT_FALSE(filter.process(scan_from({}), {std::nan(""), 0.0, 0.0}));
  EXPECT_TRUE(filter.process(scan_from({}), {}));
  EXPECT_EQ(filter.generation(), 0);
}

TEST(OdometrySync, InterpolatesAndWaitsForOdometry) {
  OdometrySyncOptions options;
  options.limits.enabled = false;  // 1 m in 100 us: pairing only, not physics
  OdometrySync sync(options);
  RangeScan early;
  early.utime = 50;
  EXPECT_FALSE(sync.add_scan(early));  // before any odometry
  ASSERT_TRUE(sync.add_odometry(100, {0.0, 0.0, 0.0}));
  RangeScan scan;
  scan.utime = 150;
  ASSERT_TRUE(sync.add_scan(scan));
  EXPECT_TRUE(sync.take_ready().empty());  // odometry at 150 not there yet
  ASSERT_TRUE(sync.add_odometry(200, {1.0, 0.0, 0.2}));
  const auto ready = sync.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_NEAR(ready[0].odometry.theta_rad, 0.1, 1e-12);
  EXPECT_NEAR(ready[0].odometry.x_m, 0.5, 0.01);
  EXPECT_FALSE(sync.add_odometry(300, {std::nan(""), 0.0, 0.0}));
  EXPECT_EQ(sync.refused_odometry(), 1u);
  EXPECT_EQ(sync.dropped_scans(), 1u);
  // A reading whose time stamp went backwards is kept; a scan of that exact
  // time gets it (as a log whose odometry and scans share time stamps).
  EXPECT_TRUE(sync.add_odometry(170, {2.0, 0.0, 0.0}));
  EXPECT_EQ(sync.out_of_order_odometry(), 1u);
  RangeScan same_time;
  same_time.utime = 170;
  sync.add_scan(same_time);
  const auto paired = sync.take_ready();
  ASSERT_EQ(paired.size(), 1u);
  EXPECT_DOUBLE_EQ(paired[0].odometry.x_m, 2.0);
}

// Odometry at 50 Hz along x at 0.5 m/s, from (x0, 0), starting at t0 (us).
namespace {
void drive(OdometrySync& sync, std::int64_t& t, double& x, int readings, double heading_variance = 0.0) {
  for (int i = 0; i < readings; ++i) {
    t += 20'000;
    x += 0.01;
    ASSERT_TRUE(sync.add_odometry(t, {x, 0.0, 0.0}, heading_variance)) << sync.why();
  }
}
}  // namespace

TEST(OdometrySync, AnAbsurdReadingIsHeldAndCountedAndMovesNothing) {
  OdometrySync sync;
  std::int64_t t = 0;
  double x = 0.0;
  drive(sync, t, x, 50);
  const Pose2 before = *sync.newest_pose();
  EXPECT_FALSE(sync.add_odometry(t + 20'000, {1e300, 0.0, 0.0}));  // not a pose at all
  EXPECT_FALSE(sync.add_odometry(t + 20'000, {x + 5.0, 0.0, 0.0}));  // 5 m in 20 ms
  EXPECT_NE(sync.why().find("not possible"), std::string::npos) << sync.why();
  EXPECT_FALSE(sync.add_odometry(t + 20'000, {x, 0.0, 2.0}));  // 2 rad in 20 ms
  EXPECT_EQ(sync.impossible_steps(), 2u);
  EXPECT_EQ(sync.refused_odometry(), 1u);
  EXPECT_DOUBLE_EQ(sync.newest_pose()->x_m, before.x_m);
  drive(sync, t, x, 10);  // and on as before: the held ones were outliers
  EXPECT_NEAR(sync.newest_pose()->x_m, before.x_m + 0.1, 1e-9);
  EXPECT_EQ(sync.odometry_resets(), 0u);
}

TEST(OdometrySync, AResetOdometryIsAnchoredWhereTheRobotWas) {
  OdometrySync sync;
  std::int64_t t = 0;
  double x = 0.0;
  drive(sync, t, x, 300);  // 3 m
  const Pose2 last = *sync.newest_pose();
  // The odometry restarts from (0, 0) at once (a jump of 3 m): held, then the
  // next reading agrees with it: a reset, no jump in what is stored.
  x = 0.0;
  t += 20'000;
  EXPECT_FALSE(sync.add_odometry(t, {0.0, 0.0, 0.0}));
  drive(sync, t, x, 10);
  EXPECT_EQ(sync.odometry_resets(), 1u);
  EXPECT_NEAR(sync.newest_pose()->x_m, last.x_m + 0.1, 1e-9);
  // Scans are paired in the first frame too.
  RangeScan scan;
  scan.utime = t;
  sync.add_scan(scan);
  drive(sync, t, x, 1);
  const auto ready = sync.take_ready();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_NEAR(ready[0].odometry.x_m, last.x_m + 0.1, 1e-9);
}

TEST(OdometrySync, AShrinkingHeadingVarianceIsARestartedOdometryEvenAfterALongGap) {
  OdometrySync sync;
  std::int64_t t = 0;
  double x = 0.0;
  for (int i = 1; i <= 200; ++i) {  // 2 m with a growing heading variance
    t += 20'000;
    x += 0.01;
    ASSERT_TRUE(sync.add_odometry(t, {x, 0.0, 0.0}, 1e-4 * i));
  }
  const Pose2 last = *sync.newest_pose();
  // The driver restarts 2 s later: (0, 0) is within 2 m/s x 2 s of (2, 0), but
  // its heading variance is back to zero: a reset, not a 2 m drive back.
  t += 2'000'000;
  x = 0.0;
  ASSERT_TRUE(sync.add_odometry(t, {0.0, 0.0, 0.0}, 0.0));
  EXPECT_EQ(sync.odometry_resets(), 1u);
  EXPECT_NEAR(sync.newest_pose()->x_m, last.x_m, 1e-9);
  drive(sync, t, x, 10, 1e-5);
  EXPECT_NEAR(sync.newest_pose()->x_m, last.x_m + 0.1, 1e-9);
}

TEST(TrajectoryRecorder, CarriesUpdatePosesForwardByOdometry) {
  ParticleFilterOptions options = small_filter(1);
  options.linear_update_m = 100.0;  // only the first scan updates
  options.angular_update_rad = 100.0;
  options.motion = {0.0, 0.0, 0.0, 0.0};
  ParticleFilter filter(options);
  TrajectoryRecorder recorder;
  const Pose2 start{1.0, 2.0, 0.5};
  filter.process(scan_from({}), start);
  recorder.record(1, filter, start);
  const Pose2 later = compose(start, {0.3, 0.1, 0.2});
  filter.process(scan_from({}), later);
  recorder.record(2, filter, later);
  const auto poses = recorder.resolve(filter);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_NEAR(poses[1].pose.x_m, later.x_m, 1e-9);
  EXPECT_NEAR(poses[1].pose.theta_rad, later.theta_rad, 1e-9);
}

}  // namespace
}  // namespace pex::slam
