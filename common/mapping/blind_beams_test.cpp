#include "mapping/blind_beams.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/scan_polygon.hpp"
#include "mapping/test_support.hpp"

namespace pex::mapping {
namespace {

constexpr float kNoEcho = 0.0f;
constexpr double kRangeMin = 0.05, kRangeMax = 20.0, kFreeRange = 4.0;

// Five beams: 0 and 4 see a wall at 3 m; 1..3 have no echo.
std::vector<float> five_beams() { return {3.0f, kNoEcho, kNoEcho, kNoEcho, 3.0f}; }

// The extents against a map whose wall stops beams 1 and 2 (at 2.5 m);
// beam 3 runs into the unknown.
std::vector<float> stopped_at_wall() { return {4.0f, 2.5f, 2.5f, 4.0f, 4.0f}; }

// (The tests of the blind rule itself leave out the first-echo rule, which
// would keep beams 1..3 of five_beams() from giving free space anyway.)
TEST(BlindBeams, ABeamWithoutAnEchoAtAKnownWallScanAfterScanIsBlindUntilItReturns) {
  BlindBeams blind({.after_stopped_scans = 2, .no_free_space_before_first_echo = false});
  auto ranges = five_beams();
  blind.observe(ranges, kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange);
  EXPECT_EQ(blind.count(), 0) << "one scan is glass at a slant as well";
  // A scan in which no beam ran into a wall (empty extents) is no evidence
  // either way: the count goes on from where it was.
  blind.observe(ranges, kRangeMin, kRangeMax, {}, kFreeRange);
  EXPECT_EQ(blind.count(), 0);
  blind.observe(ranges, kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange);
  EXPECT_EQ(blind.count(), 2);
  EXPECT_TRUE(blind.blind(1));
  EXPECT_TRUE(blind.blind(2));
  EXPECT_FALSE(blind.blind(3)) << "into the unknown: nothing says it should have seen something";
  EXPECT_FALSE(blind.blind(0));
  EXPECT_EQ(std::vector<std::uint8_t>(blind.mask().begin(), blind.mask().end()),
            (std::vector<std::uint8_t>{0, 1, 1, 0, 0}));
  EXPECT_EQ(blind.onsets(), 1);

  // Blind beams give no free space: their extent is the minimum range,
  // whatever the map says (empty extents: no wall near this time).
  const auto e = blind.extents(ranges, kRangeMin, kRangeMax, {}, kFreeRange);
  ASSERT_EQ(e.size(), ranges.size());
  EXPECT_FLOAT_EQ(e[1], static_cast<float>(kRangeMin));
  EXPECT_FLOAT_EQ(e[2], static_cast<float>(kRangeMin));
  EXPECT_FALSE(e[3] < kFreeRange) << "not blind: its free range";

  // A return on beam 1 clears it; beam 2 stays blind.
  ranges[1] = 1.5f;
  blind.observe(ranges, kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange);
  EXPECT_FALSE(blind.blind(1));
  EXPECT_TRUE(blind.blind(2));
  EXPECT_EQ(blind.count(), 1);
  // ... and beam 1 needs two more stopped scans to be blind again.
  ranges[1] = kNoEcho;
  blind.observe(ranges, kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange);
  EXPECT_FALSE(blind.blind(1));
  blind.observe(ranges, kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange);
  EXPECT_TRUE(blind.blind(1));
  EXPECT_EQ(blind.onsets(), 1) << "beam 2 stayed blind throughout: no new onset";
}

TEST(BlindBeams, OffNeverFlagsAndAnotherBeamCountStartsAfresh) {
  BlindBeams off({.after_stopped_scans = 0, .no_free_space_before_first_echo = false});
  for (int k = 0; k < 5; ++k) off.observe(five_beams(), kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange);
  EXPECT_EQ(off.count(), 0);
  EXPECT_EQ(off.extents(five_beams(), kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange), stopped_at_wall());

  BlindBeams blind({.after_stopped_scans = 1, .no_free_space_before_first_echo = false});
  blind.observe(five_beams(), kRangeMin, kRangeMax, stopped_at_wall(), kFreeRange);
  ASSERT_EQ(blind.count(), 2);
  const std::vector<float> six(6, kNoEcho);
  blind.observe(six, kRangeMin, kRangeMax, {}, kFreeRange);
  EXPECT_EQ(blind.count(), 0);
  EXPECT_EQ(std::vector<std::uint8_t>(blind.mask().begin(), blind.mask().end()), std::vector<std::uint8_t>(6, 0));
  EXPECT_TRUE(blind.extents(six, kRangeMin, kRangeMax, {}, kFreeRange).empty());
}

// A sector blind from the first scan: no wall the map holds to find it blind
// against. Its beams give no free space until each has returned an echo once;
// they are not counted blind (nothing says the laser is at fault: a robot
// starting in a hall sees no wall within range on some beams).
TEST(BlindBeams, ABeamGivesNoFreeSpaceUntilItsFirstEcho) {
  BlindBeams beams({.after_stopped_scans = 2});
  auto ranges = five_beams();
  beams.observe(ranges, kRangeMin, kRangeMax, {}, kFreeRange);
  EXPECT_EQ(beams.count(), 0);
  EXPECT_EQ(beams.never_echoed(), 3);
  EXPECT_EQ(std::vector<std::uint8_t>(beams.no_free_space_mask().begin(), beams.no_free_space_mask().end()),
            (std::vector<std::uint8_t>{0, 1, 1, 1, 0}));
  auto e = beams.extents(ranges, kRangeMin, kRangeMax, {}, kFreeRange);
  ASSERT_EQ(e.size(), ranges.size());
  for (int i : {1, 2, 3}) EXPECT_FLOAT_EQ(e[i], static_cast<float>(kRangeMin)) << "beam " << i;
  EXPECT_FALSE(e[0] < kFreeRange);

  // Beam 3 returns once; from then on a scan without its echo gives it its free range.
  ranges[3] = 2.0f;
  beams.observe(ranges, kRangeMin, kRangeMax, {}, kFreeRange);
  ranges[3] = kNoEcho;
  beams.observe(ranges, kRangeMin, kRangeMax, {}, kFreeRange);
  EXPECT_EQ(beams.never_echoed(), 2);
  e = beams.extents(ranges, kRangeMin, kRangeMax, {}, kFreeRange);
  ASSERT_EQ(e.size(), ranges.size());
  EXPECT_FALSE(e[3] < kFreeRange) << "it has seen: its free range";
  EXPECT_FLOAT_EQ(e[2], static_cast<float>(kRangeMin));

  // Off: every beam without an echo gives its free range from the first scan.
  BlindBeams off({.after_stopped_scans = 2, .no_free_space_before_first_echo = false});
  off.observe(five_beams(), kRangeMin, kRangeMax, {}, kFreeRange);
  EXPECT_EQ(off.never_echoed(), 0);
  EXPECT_TRUE(off.extents(five_beams(), kRangeMin, kRangeMax, {}, kFreeRange).empty());
}

TEST(BlindBeams, RunsAreTheAdjacentBlindBeamsInBeamOrder) {
  EXPECT_TRUE(blind_runs({}).empty());
  EXPECT_TRUE(blind_runs(std::vector<std::uint8_t>(5, 0)).empty());
  const auto runs = blind_runs(std::vector<std::uint8_t>{1, 1, 0, 0, 1, 0, 1, 1, 1});
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[0].first, 0u);
  EXPECT_EQ(runs[0].last, 1u);
  EXPECT_EQ(runs[1].first, 4u);
  EXPECT_EQ(runs[1].last, 4u);
  EXPECT_EQ(runs[2].first, 6u);
  EXPECT_EQ(runs[2].last, 8u);
}

TEST(BlindBeams, AFreeRangeThatRoundsInFloatIsNoWall) {
  // 2.1 m is below 2.1 in float: a beam that kept its free range was not
  // stopped, and must not count as evidence.
  const double free_range = 2.1;
  const std::vector<float> ranges{kNoEcho, kNoEcho};
  const std::vector<float> extents{static_cast<float>(free_range), 1.0f};
  BlindBeams blind({.after_stopped_scans = 1});
  blind.observe(ranges, kRangeMin, kRangeMax, extents, free_range);
  EXPECT_FALSE(blind.blind(0));
  EXPECT_TRUE(blind.blind(1));
}

// The sector fault's case: the laser goes blind ahead while the map holds
// the room's far wall, then turns to where the map has not been: a pillar
// there, never seen, must not be carved through by the blind beams.
TEST(BlindBeams, ABlindSectorCarvesNoWallTheMapHasNotSeen) {
  constexpr double kPi = std::numbers::pi;
  std::vector<testing::Wall> room;
  testing::add_box(room, 0, 0, 10, 4);
  std::vector<testing::Wall> world = room;
  testing::add_box(world, 4.0, 1.7, 4.6, 2.3);  // the pillar, 2 m east of the robot
  const testing::ScanSpec spec;
  ScanPolygonOptions options;
  options.range_min_m = kRangeMin;
  options.range_max_m = spec.range_max_m;
  options.free_range_m = kFreeRange;
  // Blind from -0.6 to 0.6 rad (ahead); the pillar subtends +-0.15 rad from (2, 2).
  auto blind_ahead = [&](const geometry::Pose2& pose) {
    auto ranges = testing::cast_scan(world, pose, spec);
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const double a = spec.angle_min + spec.angle_increment * static_cast<double>(i);
      if (std::abs(a) < 0.6) ranges[i] = kNoEcho;
    }
    return ranges;
  };
  auto pillar_carved = [&](bool track) {
    PolygonMap map;
    // Facing west: the west part of the room is mapped, its west wall 2 m
    // ahead; the east (the pillar) lies in the laser's rear, unseen.
    const geometry::Pose2 west{2.0, 2.0, kPi};
    const auto first = scan_to_polygon(testing::cast_scan(world, west, spec), spec.angle_min, spec.angle_increment,
                                       west, options);
    EXPECT_TRUE(first.ok);
    map.insert(first.polygon);
    BlindBeams blind({.after_stopped_scans = 2});
    // Blind now: two scans facing west, the sector's beams on the known wall.
    for (int k = 0; k < 2; ++k) {
      const auto scan = blind_ahead(west);
      const auto p = scan_to_polygon_in(map, scan, spec.angle_min, spec.angle_increment, west, options, nullptr,
                                        track ? &blind : nullptr);
      EXPECT_TRUE(p.ok);
      map.insert(p.polygon);
    }
    EXPECT_EQ(blind.count() > 0, track);
    // Turned east, the blind sector on the pillar.
    const geometry::Pose2 east{2.0, 2.0, 0.0};
    const auto scan = blind_ahead(east);
    const auto p = scan_to_polygon_in(map, scan, spec.angle_min, spec.angle_increment, east, options, nullptr,
                                      track ? &blind : nullptr);
    EXPECT_TRUE(p.ok);
    map.insert(p.polygon);
    const auto free = map.free_space();
    EXPECT_TRUE(free.ok);
    bool carved = false;
    for (const auto& polygon : free.polygons) carved = carved || bg::within(Point(4.3, 2.0), polygon.geometry);
    return carved;
  };
  EXPECT_FALSE(pillar_carved(true)) << "the blind beams gave free space through the pillar";
  EXPECT_TRUE(pillar_carved(false)) << "without the tracking the blind beams carve it (the case this guards)";
}

}  // namespace
}  // namespace pex::mapping
