#include "planning/driven_trail.hpp"

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "archive/byte_archive.hpp"
#include "planning/cspace.hpp"
#include "planning/mission.hpp"
#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

TrailUpdate update_of(std::int64_t generation, std::vector<TrailParticle> particles, int best = 0,
                      std::int64_t epoch = 7) {
  TrailUpdate u;
  u.epoch = epoch;
  u.generation = generation;
  u.best = best;
  u.particles = std::move(particles);
  return u;
}

std::vector<double> xs(const std::vector<mapping::Point>& trail) {
  std::vector<double> out;
  for (const auto& p : trail) out.push_back(p.x());
  return out;
}

TEST(DrivenTrails, EachParticleKeepsItsLineageThroughResampling) {
  DrivenTrails trails;
  ASSERT_TRUE(trails.update(update_of(0, {{{0, 0, 0}}, {{0, 1, 0}}})).ok);
  ASSERT_TRUE(trails.update(update_of(1, {{{1, 0, 0}, 0}, {{1, 1, 0}, 1}})).ok);
  // Resampling: both children of particle 1; then they part.
  ASSERT_TRUE(trails.update(update_of(2, {{{2, 1, 0}, 1}, {{2, 1.5, 0}, 1}}, 1)).ok);

  const auto t0 = trails.trail(2, 0);
  const auto t1 = trails.trail(2, 1);
  ASSERT_TRUE(t0 && t1);
  EXPECT_EQ(xs(*t0), (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(xs(*t1), (std::vector<double>{0, 1, 2}));
  EXPECT_DOUBLE_EQ((*t0)[1].y(), 1.0) << "particle 0 of generation 2 descends from particle 1";
  EXPECT_DOUBLE_EQ((*t1)[2].y(), 1.5);
  EXPECT_EQ(trails.best_trail().back().y(), 1.5);
  // An older generation is still there, as it was.
  const auto old = trails.trail(1, 0);
  ASSERT_TRUE(old);
  EXPECT_DOUBLE_EQ(old->back().y(), 0.0);
  EXPECT_FALSE(trails.trail(2, 2)) << "no such particle";
  EXPECT_FALSE(trails.trail(5, 0)) << "no such generation";
}

TEST(DrivenTrails, AStandingRobotAddsNoPoint) {
  DrivenTrailOptions options;
  options.min_spacing_m = 0.05;
  DrivenTrails trails(options);
  ASSERT_TRUE(trails.update(update_of(0, {{{0, 0, 0}}})).ok);
  ASSERT_TRUE(trails.update(update_of(1, {{{0.01, 0, 0.5}, 0}})).ok);
  ASSERT_TRUE(trails.update(update_of(2, {{{0.06, 0, 0.5}, 0}})).ok);
  EXPECT_EQ(xs(trails.best_trail()), (std::vector<double>{0, 0.06}));
}

TEST(DrivenTrails, AMissedUpdateGivesEveryParticleTheBestTrail) {
  DrivenTrails trails;
  ASSERT_TRUE(trails.update(update_of(0, {{{0, 0, 0}}, {{0, 5, 0}}}, 1)).ok);
  // Generation 1 was not seen: the parents of 2 index particles unknown here.
  const auto r = trails.update(update_of(2, {{{1, 5, 0}, 0}, {{1, 6, 0}, 0}}));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.resynced);
  for (int i = 0; i < 2; ++i) {
    const auto t = trails.trail(2, i);
    ASSERT_TRUE(t);
    ASSERT_EQ(t->size(), 2u);
    EXPECT_DOUBLE_EQ(t->front().y(), 5.0) << "the best (particle 1) trail of generation 0";
  }
}

TEST(DrivenTrails, ASlamRestoredFromAnOlderCheckpointCountsItsGenerationsAgain) {
  DrivenTrails trails;
  for (int g = 0; g <= 5; ++g) ASSERT_TRUE(trails.update(update_of(g, {{{g * 1.0, 0, 0}, 0}})).ok);
  // The same epoch, back at generation 3 (its checkpoint), on another path.
  const auto r = trails.update(update_of(3, {{{5, 1, 0}, 0}}));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.resynced);
  ASSERT_TRUE(trails.update(update_of(4, {{{5, 2, 0}, 0}})).ok);
  const auto t = trails.trail(4, 0);
  ASSERT_TRUE(t);
  EXPECT_DOUBLE_EQ(t->back().y(), 2.0) << "generation 4 of the lineage after the restore, not the one before";
  EXPECT_EQ(t->size(), 8u) << "the best trail held, then the restored lineage's points";
  EXPECT_FALSE(trails.trail(5, 0)) << "the old lineage's generations are gone";
}

TEST(DrivenTrails, ACheckpointCarriesTheBestTrailAcrossARestart) {
  DrivenTrails before;
  EXPECT_EQ(before.checkpoint(), "") << "nothing held, nothing to write";
  ASSERT_TRUE(before.update(update_of(0, {{{0, 0, 0}}, {{0, 5, 0}}})).ok);
  ASSERT_TRUE(before.update(update_of(1, {{{1, 0, 0}, 0}, {{1, 5, 0}, 1}}, 1)).ok);
  const std::string bytes = before.checkpoint();
  ASSERT_FALSE(bytes.empty());

  DrivenTrails after;
  ASSERT_EQ(after.restore(bytes), "");
  EXPECT_EQ(after.newest_generation(), std::optional<std::int64_t>(1));
  // The best trail (particle 1's) stands in for every particle's at its generation.
  for (int particle : {0, 1, 29}) {
    const auto t = after.trail(1, particle);
    ASSERT_TRUE(t) << particle;
    EXPECT_EQ(xs(*t), (std::vector<double>{0, 1}));
    EXPECT_DOUBLE_EQ(t->back().y(), 5.0);
  }
  // SLAM goes on with three particles, whose parents index particles unknown
  // here: a resync on the restored trail, not a refusal.
  const auto r = after.update(update_of(2, {{{2, 5, 0}, 1}, {{2, 6, 0}, 1}, {{2, 7, 0}, 0}}, 2));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.resynced);
  for (int particle = 0; particle < 3; ++particle) {
    const auto t = after.trail(2, particle);
    ASSERT_TRUE(t);
    EXPECT_EQ(xs(*t), (std::vector<double>{0, 1, 2}));
    EXPECT_DOUBLE_EQ((*t)[1].y(), 5.0) << "the restored best trail, then the particle's own point";
  }
  EXPECT_DOUBLE_EQ(after.best_trail().back().y(), 7.0);

  // A SLAM of another epoch: the restored trail is of another frame.
  DrivenTrails other;
  ASSERT_EQ(other.restore(bytes), "");
  const auto r2 = other.update(update_of(0, {{{9, 9, 0}}}, 0, /*epoch=*/8));
  ASSERT_TRUE(r2.ok);
  EXPECT_TRUE(r2.new_epoch);
  EXPECT_EQ(other.best_trail().size(), 1u);
}

TEST(DrivenTrails, ABadCheckpointIsRefusedAndChangesNothing) {
  DrivenTrails source;
  ASSERT_TRUE(source.update(update_of(0, {{{0, 0, 0}}})).ok);
  ASSERT_TRUE(source.update(update_of(1, {{{1, 0, 0}, 0}})).ok);
  const std::string good = source.checkpoint();

  DrivenTrails trails;
  ASSERT_TRUE(trails.update(update_of(4, {{{4, 4, 0}}})).ok);
  auto nan_point = [] {
    archive::ByteWriter w;
    w.put<std::int64_t>(7);
    w.put<std::int64_t>(1);
    w.put<std::uint64_t>(1);
    w.put<double>(std::nan(""));
    w.put<double>(0.0);
    return archive::seal("PEXTRAIL", 1, w.bytes());
  };
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;
  for (const std::string& bad : {std::string(), good.substr(0, good.size() - 3), flipped, nan_point(),
                                 std::string("polyexplore-mission 1\nend\n")}) {
    EXPECT_NE(trails.restore(bad), "");
    EXPECT_EQ(trails.newest_generation(), std::optional<std::int64_t>(4));
    EXPECT_EQ(xs(trails.best_trail()), (std::vector<double>{4}));
  }
  DrivenTrailOptions small;
  small.max_points = 1;
  DrivenTrails capped(small);
  EXPECT_NE(capped.restore(good), "") << "more points than this keeper gives out";
}

TEST(DrivenTrails, AnotherEpochStartsAfresh) {
  DrivenTrails trails;
  ASSERT_TRUE(trails.update(update_of(0, {{{0, 0, 0}}})).ok);
  ASSERT_TRUE(trails.update(update_of(1, {{{1, 0, 0}, 0}})).ok);
  const auto r = trails.update(update_of(1, {{{9, 9, 0}, 0}}, 0, /*epoch=*/8));
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(r.new_epoch);
  EXPECT_EQ(trails.best_trail().size(), 1u);
  EXPECT_DOUBLE_EQ(trails.best_trail().front().x(), 9.0);
  EXPECT_FALSE(trails.trail(0, 0)) << "the old frame's generations are gone";
}

TEST(DrivenTrails, ARepublishedGenerationReplacesItself) {
  DrivenTrails trails;
  ASSERT_TRUE(trails.update(update_of(0, {{{0, 0, 0}}})).ok);
  ASSERT_TRUE(trails.update(update_of(1, {{{1, 0, 0}, 0}})).ok);
  auto again = update_of(1, {{{1.5, 0, 0}, 0}});
  again.republished = true;
  const auto r = trails.update(again);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_FALSE(r.resynced);
  EXPECT_EQ(xs(trails.best_trail()), (std::vector<double>{0, 1, 1.5}));
  ASSERT_TRUE(trails.update(update_of(2, {{{2, 0, 0}, 0}})).ok);
  EXPECT_EQ(xs(trails.best_trail()), (std::vector<double>{0, 1, 1.5, 2}));
}

TEST(DrivenTrails, BadUpdatesAreRefusedAndChangeNothing) {
  DrivenTrailOptions options;
  options.max_particles = 3;
  DrivenTrails trails(options);
  ASSERT_TRUE(trails.update(update_of(0, {{{0, 0, 0}}, {{0, 1, 0}}})).ok);
  const std::vector<TrailUpdate> bad = {
      update_of(1, {}),
      update_of(1, {{{1, 0, 0}, 0}, {{1, 0, 0}, 0}, {{1, 0, 0}, 0}, {{1, 0, 0}, 0}}),
      update_of(1, {{{NAN, 0, 0}, 0}}),
      update_of(1, {{{1, 0, 0}, 0}}, /*best=*/1),
      update_of(1, {{{1, 0, 0}, 2}}),
      update_of(1, {{{1, 0, 0}, -1}}),
  };
  for (const auto& u : bad) {
    const auto r = trails.update(u);
    EXPECT_FALSE(r.ok);
    EXPECT_FALSE(r.error.empty());
  }
  EXPECT_EQ(trails.newest_generation(), 0);
  ASSERT_TRUE(trails.update(update_of(1, {{{1, 0, 0}, 1}})).ok) << "the next good update follows on";
  EXPECT_DOUBLE_EQ(trails.best_trail().front().y(), 1.0);
}

TEST(DrivenTrails, OnlyTheNewestGenerationsAreKept) {
  DrivenTrailOptions options;
  options.kept_generations = 3;
  DrivenTrails trails(options);
  for (int g = 0; g < 6; ++g) ASSERT_TRUE(trails.update(update_of(g, {{{g * 1.0, 0, 0}, 0}})).ok);
  EXPECT_FALSE(trails.trail(2, 0));
  ASSERT_TRUE(trails.trail(3, 0));
  EXPECT_EQ(trails.trail(3, 0)->size(), 4u) << "the trail itself keeps every point";
}

TEST(DrivenTrails, ALongTrailIsCappedAndReleasedWithoutRecursion) {
  DrivenTrailOptions options;
  options.max_points = 1000;
  options.kept_generations = 1;
  {
    DrivenTrails trails(options);
    // 120 km at 6 cm, 4 particles sharing it: released node by node at the
    // end (recursion through 2,000,000 shared pointers overflows the stack).
    for (int g = 0; g < 2'000'000; ++g) {
      std::vector<TrailParticle> particles(4, TrailParticle{{g * 0.06, 0.0, 0.0}, 0});
      ASSERT_TRUE(trails.update(update_of(g, std::move(particles))).ok);
    }
    const auto t = trails.best_trail();
    ASSERT_EQ(t.size(), 1000u);
    EXPECT_DOUBLE_EQ(t.back().x(), 1'999'999 * 0.06) << "the newest points";
  }
}

TEST(TrailCorridor, IsTheBandOfItsHalfWidthAboutTheTrail) {
  const std::vector<mapping::Point> trail{{0, 0}, {4, 0}, {4, 3}};
  const auto corridor = trail_corridor(trail, 0.05);
  ASSERT_FALSE(corridor.empty());
  // 7 m long, 0.1 m wide, with the round ends and the join's quarter disk.
  const double expected = 7.0 * 0.1 + std::numbers::pi * 0.05 * 0.05 + 0.25 * std::numbers::pi * 0.05 * 0.05;
  namespace bg = boost::geometry;
  EXPECT_NEAR(bg::area(corridor), expected, 0.003);
  EXPECT_TRUE(bg::covered_by(mapping::Point(2, 0.04), corridor));
  EXPECT_FALSE(bg::covered_by(mapping::Point(2, 0.06), corridor));
  // A robot that has not moved: the disk about where it stands (chords
  // within 1 mm of the circle: at most 2 pi r x 1 mm less).
  const double disk = bg::area(trail_corridor({{1, 1}}, 0.05));
  EXPECT_LE(disk, std::numbers::pi * 0.05 * 0.05);
  EXPECT_GE(disk, std::numbers::pi * 0.05 * 0.05 - 2 * std::numbers::pi * 0.05 * 1e-3);
  EXPECT_TRUE(trail_corridor({}, 0.05).empty());
  EXPECT_TRUE(trail_corridor(trail, 0.0).empty());
  EXPECT_TRUE(trail_corridor({{NAN, 0}, {1, 0}}, 0.05).empty()) << "refused, not half drawn";
}

TEST(TrailCorridor, JoinsTheCSpaceAcrossAGapTheMapShut) {
  // Room A and room B joined by a slit 0.3 m wide, narrower than the 0.5 m
  // robot in this map; the robot drove through it all the same (the map's
  // gap is narrower than the world's).
  const auto map = testing::a_room_cut_off_behind_a_slit();
  const auto options = testing::disk(0.25);
  ConfigurationSpace without;
  ASSERT_TRUE(without.build(map, options).ok);
  const mapping::Point a(8, 2), b(13, 2);
  EXPECT_NE(without.piece_of(a), without.piece_of(b));

  const std::vector<mapping::Point> trail{{7, 1}, {8, 2}, {13, 2}};
  const DrivenWay way{trail, 0.05};
  ConfigurationSpace with;
  ASSERT_TRUE(with.build(map, options, nullptr, &way).ok);
  ASSERT_GE(with.piece_of(a), 0);
  EXPECT_EQ(with.piece_of(a), with.piece_of(b));
  EXPECT_TRUE(with.covers(mapping::Point(10.5, 2.04)));
  EXPECT_FALSE(with.covers(mapping::Point(10.5, 2.08))) << "only the corridor, not the gap, is added";
}

TEST(TrailCorridor, AddsNothingWhereItJoinsNoTwoPieces) {
  // The trail runs along room A's south wall, 0.2 m from it: outside the
  // C-space of a 0.25 m robot (the map's wall is 5 cm off where the robot
  // found it), but it leads nowhere the C-space does not already reach.
  const auto map = testing::a_room_cut_off_behind_a_slit();
  const auto options = testing::disk(0.25);
  ConfigurationSpace without;
  ASSERT_TRUE(without.build(map, options).ok);
  const std::vector<mapping::Point> trail{{1, 0.2}, {3, 0.2}, {3, 1}};
  const DrivenWay way{trail, 0.05};
  ConfigurationSpace with;
  ASSERT_TRUE(with.build(map, options, nullptr, &way).ok);
  EXPECT_FALSE(with.covers(mapping::Point(2, 0.2)));
  EXPECT_EQ(with.edges().size(), without.edges().size());
  EXPECT_EQ(with.polygons().size(), without.polygons().size());
}

// The same part of the way, but the robot is still out there: the way ends
// in the band along the wall the C-space leaves out (SLAM moved the pose, or
// the wall, by 5 cm). With keep_where_the_robot_stands (the planner's second
// try, for a robot farther out than a start may snap), that part is kept:
// where the robot stands and its way back into the C-space.
TEST(TrailCorridor, KeepsThePartTheRobotStandsInWhenAsked) {
  const auto map = testing::a_room_cut_off_behind_a_slit();
  const auto options = testing::disk(0.25);
  ConfigurationSpace without;
  ASSERT_TRUE(without.build(map, options).ok);
  const mapping::Point robot(3, 0.2), room(3, 1);
  EXPECT_FALSE(without.covers(robot));
  const std::vector<mapping::Point> trail{room, {1, 0.2}, robot};
  DrivenWay way{trail, 0.05};
  ConfigurationSpace plain;
  ASSERT_TRUE(plain.build(map, options, nullptr, &way).ok);
  EXPECT_FALSE(plain.covers(robot)) << "not asked: a part that joins nothing";
  way.keep_where_the_robot_stands = true;
  ConfigurationSpace with;
  ASSERT_TRUE(with.build(map, options, nullptr, &way).ok);
  EXPECT_TRUE(with.covers(robot));
  EXPECT_TRUE(with.covers(mapping::Point(2, 0.2)));
  ASSERT_GE(with.piece_of(robot), 0);
  EXPECT_EQ(with.piece_of(robot), with.piece_of(room)) << "joined to the room it leads back to";
  EXPECT_EQ(with.polygons().size(), without.polygons().size());
}

// The C-space keeps only the stretches of the way that come near its edges
// or run outside it (way_near_or_outside): the rest lies deep inside, and its
// corridor adds nothing. The C-space must be the same as with the corridor
// of the whole way, on ways that run deep inside, along walls, through the
// slit and through walls (the map's walls where SLAM put them, not where
// the robot found them).
TEST(TrailCorridor, TheWayDeepInsideTheCSpaceChangesNothing) {
  namespace bg = boost::geometry;
  const auto map = testing::a_room_cut_off_behind_a_slit();
  const auto options = testing::disk(0.25);
  ConfigurationSpace without;
  ASSERT_TRUE(without.build(map, options).ok);
  const auto cspace = mapping::geometry_of(without.polygons());
  std::mt19937 random(7);
  std::uniform_real_distribution<double> turn(-0.6, 0.6);
  int dropped_somewhere = 0, bridged = 0;
  for (int walk = 0; walk < 24; ++walk) {
    std::vector<mapping::Point> trail{{std::uniform_real_distribution<double>(0.5, 15.5)(random),
                                       std::uniform_real_distribution<double>(0.5, 3.5)(random)}};
    double heading = std::uniform_real_distribution<double>(-3.14, 3.14)(random);
    for (int step = 0; step < 600; ++step) {
      heading += turn(random);
      const auto& p = trail.back();
      // Kept on the map's box (walls and the slit crossed freely) by turning back at its sides.
      double x = p.x() + 0.05 * std::cos(heading), y = p.y() + 0.05 * std::sin(heading);
      if (x < 0.1 || x > 15.9 || y < 0.1 || y > 3.9) {
        heading += 3.14159;
        x = p.x();
        y = p.y();
      }
      trail.emplace_back(x, y);
    }
    const DrivenWay way{trail, 0.05};
    const auto stretches = way_near_or_outside(cspace, way);
    std::size_t kept = 0;
    for (const auto& s : stretches) kept += s.size();
    dropped_somewhere += kept < trail.size();

    const auto whole = with_bridges(cspace, trail_corridor(trail, 0.05));
    ASSERT_TRUE(whole.has_value());
    ConfigurationSpace with;
    ASSERT_TRUE(with.build(map, options, nullptr, &way).ok) << "walk " << walk;
    const auto built = mapping::geometry_of(with.polygons());
    EXPECT_NEAR(bg::area(built), bg::area(*whole), 1e-6) << "walk " << walk;
    EXPECT_EQ(built.size(), whole->size()) << "walk " << walk;
    bridged += bg::area(*whole) > bg::area(cspace) + 1e-6;
  }
  EXPECT_GT(dropped_somewhere, 12) << "most walks have stretches deep inside the C-space";
  EXPECT_GT(bridged, 0) << "some walks cross the slit or a wall and join the rooms";
}

TEST(TrailCorridor, AWayOutsideAnEmptyCSpaceIsKeptWhole) {
  const std::vector<mapping::Point> trail{{0, 0}, {1, 0}, {1, 1}};
  const auto stretches = way_near_or_outside({}, DrivenWay{trail, 0.05});
  ASSERT_EQ(stretches.size(), 1u);
  EXPECT_EQ(stretches[0].size(), 3u);
  const std::vector<mapping::Point> one{{0.5, 0.5}};
  ASSERT_EQ(way_near_or_outside({}, DrivenWay{one, 0.05}).size(), 1u);
}

TEST(TrailCorridor, AWayWithAPointNotFiniteAddsNothing) {
  const auto map = testing::a_room_cut_off_behind_a_slit();
  const auto options = testing::disk(0.25);
  ConfigurationSpace without, with;
  ASSERT_TRUE(without.build(map, options).ok);
  const std::vector<mapping::Point> trail{{7, 1}, {8, 2}, {NAN, 2}, {13, 2}};
  const DrivenWay way{trail, 0.05};
  ASSERT_TRUE(with.build(map, options, nullptr, &way).ok);
  EXPECT_EQ(with.polygons().size(), without.polygons().size());
  EXPECT_EQ(with.edges().size(), without.edges().size());
}

TEST(TrailCorridor, ATightPlanGoesBackTheWayTheRobotCame) {
  // The robot is in room B; room A's frontier (its west wall) is behind the slit.
  constexpr auto O = mapping::EdgeType::kObstacle;
  constexpr auto F = mapping::EdgeType::kFrontier;
  auto map = testing::a_room_cut_off_behind_a_slit();
  // Room B's far wall is seen (obstacle); room A's west wall is not (frontier).
  map = {testing::typed_polygon(
      testing::RingSpec{{mapping::Point(0, 0), mapping::Point(10, 0), mapping::Point(10, 1.85),
                         mapping::Point(11, 1.85), mapping::Point(11, 0), mapping::Point(16, 0),
                         mapping::Point(16, 4), mapping::Point(11, 4), mapping::Point(11, 2.15),
                         mapping::Point(10, 2.15), mapping::Point(10, 4), mapping::Point(0, 4)},
                        {O, O, O, O, O, O, O, O, O, O, O, F}},
      {testing::rectangle_hole(4, 1.5, 5, 2.5)})};
  PlanRequest request;
  request.map = std::make_shared<const mapping::TypedMultiPolygon>(map);
  request.pose = {13.5, 2.0, 0.0};
  request.options.cspace = testing::disk(0.25);
  request.options.approach_range_m = 0.0;
  request.tight = true;
  request.trail = std::make_shared<const std::vector<mapping::Point>>(
      std::vector<mapping::Point>{{2, 3}, {7, 2}, {13.5, 2}});

  const PlanResult with = compute_plan(request);
  ASSERT_TRUE(with.plan.ok) << with.plan.error;
  const GoalCandidate* goal = with.plan.best_candidate();
  ASSERT_NE(goal, nullptr) << "room A is reachable along the trail";
  EXPECT_LT(goal->position.x(), 1.0);

  request.tight = false;  // a plan with the full margin does not use the trail
  const PlanResult full = compute_plan(request);
  ASSERT_TRUE(full.plan.ok) << full.plan.error;
  EXPECT_EQ(full.plan.best_candidate(), nullptr);
  request.tight = true;
  request.options.trail_corridor_m = 0.0;  // off
  EXPECT_EQ(compute_plan(request).plan.best_candidate(), nullptr);
}

}  // namespace
}  // namespace pex::planning
