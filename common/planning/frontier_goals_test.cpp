#include "planning/frontier_goals.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "planning/cspace.hpp"
#include "planning/test_maps.hpp"

namespace pex::planning {
namespace {

namespace bg = boost::geometry;
using E = mapping::EdgeType;
using testing::RingSpec;
using testing::typed_polygon;

// An L-shaped room whose frontier runs along several edges (a chain bending
// around corners), with a short frontier sliver and a hole that is all frontier.
mapping::TypedMultiPolygon l_room() {
  RingSpec outer{{Point(0, 0), Point(30, 0), Point(30, 10), Point(10, 10), Point(10, 30), Point(0, 30)},
                 {E::kFrontier, E::kFrontier, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle}};
  RingSpec hole{{Point(3, 3), Point(3, 3.2), Point(3.2, 3.2), Point(3.2, 3)},
                {E::kFrontier, E::kFrontier, E::kFrontier, E::kFrontier}};
  return {typed_polygon(outer, {hole})};
}

TEST(FrontierChains, RunsOfFrontierEdgesAcrossTheRingStart) {
  const auto chains = frontier_chains(l_room());
  ASSERT_EQ(chains.size(), 3u);
  // Edges 0..2 (30 + 10 + 20 m) form one chain; edge 4 (10 -> 0 along the top,
  // 10 m) another; the hole is a closed chain of 0.8 m.
  EXPECT_NEAR(chains[0].length_m, 60.0, 1e-12);
  EXPECT_FALSE(chains[0].closed);
  EXPECT_NEAR(chains[1].length_m, 10.0, 1e-12);
  EXPECT_TRUE(chains[2].closed);
  EXPECT_NEAR(chains[2].length_m, 0.8, 1e-12);
}

// A 10 x 10 m room whose bottom side is frontier, with a desk (a 2 x 1 m
// hole) seen from three sides, and a 3 x 4 m hole (a store room seen from
// outside, its left side unseen) holding a 1 x 1 m island of free space
// (seen through a window) that has a 0.6 x 0.6 m hole of its own.
mapping::TypedMultiPolygon room_with_enclosed_unknown() {
  using testing::rectangle;
  using testing::rectangle_hole;
  auto desk = rectangle_hole(2, 2, 4, 3);
  desk.types = {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle};  // its right side unseen
  auto store = rectangle_hole(6, 5, 9, 9);
  store.types = {E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle};
  auto crate = rectangle_hole(7.2, 6.2, 7.8, 6.8);
  crate.types = {E::kFrontier, E::kFrontier, E::kFrontier, E::kFrontier};
  return {typed_polygon(rectangle(0, 0, 10, 10, {E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle}),
                        {desk, store}),
          typed_polygon(rectangle(7, 6, 8, 7, {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle}), {crate})};
}

TEST(FrontierChains, AChainOnAHoleEnclosesTheHoleLessTheMapInsideIt) {
  const auto chains = frontier_chains(room_with_enclosed_unknown());
  ASSERT_EQ(chains.size(), 5u);
  // In map order: the room's outside, the desk, the store room, the island's
  // outside (in the store room), the island's hole.
  EXPECT_TRUE(std::isinf(chains[0].enclosed_area_m2));  // beyond the room's open side: unbounded
  EXPECT_NEAR(chains[1].enclosed_area_m2, 2.0, 1e-9);
  EXPECT_NEAR(chains[2].enclosed_area_m2, 12.0 - 1.0, 1e-9);  // the island (with its hole) is not unknown
  EXPECT_NEAR(chains[3].enclosed_area_m2, 11.0, 1e-9);        // the island borders the store room's unknown
  EXPECT_NEAR(chains[4].enclosed_area_m2, 0.36, 1e-9);
  const auto areas = enclosed_areas(room_with_enclosed_unknown());
  ASSERT_EQ(areas.size(), 2u);
  ASSERT_EQ(areas[0].size(), 3u);
  ASSERT_EQ(areas[1].size(), 2u);
  EXPECT_TRUE(std::isinf(areas[0][0]));
}

TEST(EnclosedAreas, ManyPolygonsInALongHoleAreLookedUpWithinABudgetNeverTakenAsEnclosed) {
  // Few islands: every one is placed, and subtracted from the hole.
  int not_placed = -1;
  const auto few = testing::islands_in_a_long_hole(1000, 20);
  const auto areas = enclosed_areas(few, &not_placed);
  EXPECT_EQ(not_placed, 0);
  double expected = std::abs(bg::area(few[0].geometry.inners()[0]));
  for (std::size_t p = 1; p < few.size(); ++p) {
    expected -= std::abs(bg::area(few[p].geometry.outer()));
    EXPECT_NEAR(areas[p][0], areas[0][1], 1e-9);  // an island borders the hole's region
  }
  EXPECT_NEAR(areas[0][1], expected, 1e-6);
  // 3,000 islands: 3 tests each against the 1,000-vertex ring would read
  // 9 million vertices. Past the budget, islands are not placed, and what
  // they could have been subtracted from is unbounded: no frontier of this
  // map can be taken as enclosed by a region too small.
  const auto many = testing::islands_in_a_long_hole(1000, 3000);
  const auto budgeted = enclosed_areas(many, &not_placed);
  EXPECT_GT(not_placed, 0);
  EXPECT_LT(not_placed, 3000);
  EXPECT_TRUE(std::isinf(budgeted[0][1]));
  for (std::size_t p = 1; p < many.size(); ++p) EXPECT_TRUE(std::isinf(budgeted[p][0])) << p;
}

TEST(FrontierChains, ChainWrappingPastVertexZeroIsOneChain) {
  // Frontier on the last and the first edge: one chain through vertex 0.
  RingSpec outer{{Point(0, 0), Point(4, 0), Point(4, 4), Point(0, 4)},
                 {E::kFrontier, E::kObstacle, E::kObstacle, E::kFrontier}};
  const auto chains = frontier_chains({typed_polygon(outer)});
  ASSERT_EQ(chains.size(), 1u);
  EXPECT_NEAR(chains[0].length_m, 8.0, 1e-12);
  EXPECT_EQ(chains[0].points.front().x(), 0.0);
  EXPECT_EQ(chains[0].points.front().y(), 4.0);
  EXPECT_EQ(chains[0].points.back().x(), 4.0);
}

TEST(FrontierCandidates, TheirArcsSplitEachChainAndHoldTheirPoint) {
  FrontierGoalOptions options;
  options.sensor_range_m = 4.0;
  const auto chains = frontier_chains(l_room());
  const auto candidates = frontier_candidates(chains, options);
  std::vector<double> covered(chains.size(), 0.0);  // arc length covered so far, chain by chain
  for (const auto& c : candidates) {
    const auto& chain = chains[static_cast<std::size_t>(c.chain)];
    EXPECT_NEAR(c.arc_from_m, covered[static_cast<std::size_t>(c.chain)], 1e-9);  // in order, no gap
    EXPECT_GT(c.arc_to_m, c.arc_from_m);
    EXPECT_LE(c.arc_to_m - c.arc_from_m, 2.0 * options.sensor_range_m + 1e-9);
    const Point middle = point_at_arc_length(chain.points, 0.5 * (c.arc_from_m + c.arc_to_m));
    EXPECT_NEAR(distance(middle, c.point), 0.0, 1e-9);
    covered[static_cast<std::size_t>(c.chain)] = c.arc_to_m;
  }
  for (std::size_t k = 0; k < chains.size(); ++k) {
    if (chains[k].length_m < options.min_frontier_length_m) continue;
    EXPECT_NEAR(covered[k], chains[k].length_m, 1e-9);
  }
}

TEST(FrontierCandidates, EveryFrontierPointIsWithinSensorRange) {
  FrontierGoalOptions options;
  options.sensor_range_m = 4.0;
  options.min_frontier_length_m = 1.0;
  const auto map = l_room();
  const auto chains = frontier_chains(map);
  int dropped = -1;
  const auto candidates = frontier_candidates(chains, options, &dropped);
  EXPECT_EQ(dropped, 1);  // the 0.8 m hole
  // ceil(60 / 8) + ceil(10 / 8)
  EXPECT_EQ(candidates.size(), 8u + 2u);
  // Sample every frontier edge of the map itself every 1 cm.
  int sampled = 0;
  mapping::for_each_edge(map, [&](const Point& a, const Point& b, E type) {
    if (type != E::kFrontier) return;
    const double len = distance(a, b);
    if (len < 1.0 && std::abs(a.x() - 3.1) < 0.2) return;  // the dropped sliver
    for (double s = 0.0; s <= len; s += 0.01) {
      const Point p(a.x() + (b.x() - a.x()) * s / len, a.y() + (b.y() - a.y()) * s / len);
      double nearest = std::numeric_limits<double>::infinity();
      for (const auto& c : candidates) nearest = std::min(nearest, distance(p, c.point));
      ASSERT_LE(nearest, options.sensor_range_m + 1e-9) << p.x() << "," << p.y();
      ++sampled;
    }
  });
  EXPECT_GT(sampled, 6000);
  // Candidates lie on their chain.
  for (const auto& c : candidates) {
    double d = std::numeric_limits<double>::infinity();
    const auto& pts = chains[static_cast<std::size_t>(c.chain)].points;
    for (std::size_t i = 1; i < pts.size(); ++i)
      d = std::min(d, distance(c.point, closest_point_on_segment(c.point, pts[i - 1], pts[i])));
    EXPECT_LT(d, 1e-9);
  }
}

TEST(FrontierCandidates, ShortChainGetsOneCandidateInTheMiddle) {
  FrontierChain chain{{Point(0, 0), Point(2, 0), Point(2, 2)}, false, 4.0};
  const auto candidates = frontier_candidates({chain}, FrontierGoalOptions{5.0, 0.3});
  ASSERT_EQ(candidates.size(), 1u);
  EXPECT_NEAR(candidates[0].point.x(), 2.0, 1e-12);
  EXPECT_NEAR(candidates[0].point.y(), 0.0, 1e-12);
}

TEST(FrontierCandidates, NoFrontierNoCandidate) {
  const auto map = mapping::TypedMultiPolygon{typed_polygon(testing::rectangle(0, 0, 5, 5))};
  EXPECT_TRUE(frontier_chains(map).empty());
  EXPECT_TRUE(frontier_candidates(frontier_chains(map), {}).empty());
}

// A 6 x 4 m room whose bottom wall has a 1.6 x 0.8 m desk standing 5 cm in
// front of it (x 2..3.6): the laser saw the desk's front and right flank and
// the wall on both sides, not the desk's left flank (a frontier from the wall
// up to the desk's corner) nor the 5 cm behind it (a short frontier down the
// right flank's end).
mapping::TypedMultiPolygon room_with_a_desk_against_the_wall() {
  RingSpec outer{{Point(0, 0), Point(2, 0), Point(2, 0.85), Point(3.6, 0.85), Point(3.6, 0.05), Point(3.6, 0),
                  Point(6, 0), Point(6, 4), Point(0, 4)},
                 {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle,
                  E::kObstacle, E::kObstacle}};
  return {typed_polygon(outer)};
}

WalledBayOptions bays_below(double max_area_m2) {
  WalledBayOptions o;
  o.max_area_m2 = max_area_m2;
  return o;
}

TEST(WalledBays, ADesksFlankAgainstAWallLiesInABayOfTheDesksSize) {
  const auto map = room_with_a_desk_against_the_wall();
  auto chains = frontier_chains(map);
  ASSERT_EQ(chains.size(), 2u);  // the desk's left flank, the 5 cm behind its right end
  for (const auto& c : chains) EXPECT_TRUE(std::isinf(c.enclosed_area_m2));  // on the room's outer ring
  find_walled_bays(map, chains, bays_below(2.0));
  // The lid runs along the wall from (2, 0) to (3.6, 0): the bay is the desk
  // and the 5 cm strip behind it, 1.6 x 0.85 m.
  EXPECT_NEAR(chains[0].bay_area_m2, 1.6 * 0.85, 1e-9);
  EXPECT_NEAR(chains[1].bay_area_m2, 1.6 * 0.85, 1e-9);
  EXPECT_NEAR(chains[0].enclosed_or_bay_area_m2(), 1.6 * 0.85, 1e-9);
  // Bays of that size or more are not looked for; off by default.
  auto again = frontier_chains(map);
  find_walled_bays(map, again, bays_below(1.36));
  EXPECT_TRUE(std::isinf(again[0].bay_area_m2));
  find_walled_bays(map, again, WalledBayOptions{});
  EXPECT_TRUE(std::isinf(again[0].bay_area_m2));
  // A lid longer than allowed: none.
  WalledBayOptions short_lid = bays_below(2.0);
  short_lid.max_lid_m = 1.5;
  find_walled_bays(map, again, short_lid);
  EXPECT_TRUE(std::isinf(again[0].bay_area_m2));
}

TEST(WalledBays, AFlanksFrontierEndingBelowTheWallsLineStillLiesInTheBay) {
  // As the mapper draws a desk 5 cm off a wall (floor120, far wall): the
  // wall's band lies at y 0.05, each flank's frontier runs down to 3-4 cm
  // below that line, and the right one meets the wall through steps of the
  // band 6 cm long, so the flank crosses the lid 6 cm from its end.
  RingSpec outer{{Point(0, 0.05), Point(2.0, 0.056), Point(2.008, 0.017), Point(2.0, 0.85), Point(3.6, 0.85),
                  Point(3.725, 0.019), Point(3.725, 0.039), Point(3.782, 0.047), Point(3.782, 0.062), Point(6, 0.05),
                  Point(6, 4), Point(0, 4)},
                 {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle,
                  E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle}};
  mapping::TypedMultiPolygon map{typed_polygon(outer)};
  auto chains = frontier_chains(map);
  ASSERT_EQ(chains.size(), 2u);
  find_walled_bays(map, chains, bays_below(2.0));
  // The lid from (2, 0.056) to (3.782, 0.062): the desk's 1.6 x 0.79 m above
  // it and the slant of the right flank, 1.31 m2.
  EXPECT_NEAR(chains[0].bay_area_m2, 1.31, 0.01);
  EXPECT_NEAR(chains[1].bay_area_m2, chains[0].bay_area_m2, 1e-12);
  // The same steps 10 cm below the line: more than the band's noise, no bay.
  auto& ring = map[0].geometry.outer();
  ring[5] = Point(3.725, -0.05);
  ring[6] = Point(3.725, -0.03);
  chains = frontier_chains(map);
  find_walled_bays(map, chains, bays_below(2.0));
  EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
  EXPECT_TRUE(std::isinf(chains[1].bay_area_m2));
}

TEST(WalledBays, ADoorTheLaserSawThroughIsNoBay) {
  // The bottom wall has a 1 m door (x 2..3) the laser saw through: the free
  // space runs through it into a wedge of the room below, whose far wall it
  // saw. The door's jambs are in line, but the loop round the wedge encloses
  // free space, not unknown.
  RingSpec outer{{Point(0, 0), Point(2, 0), Point(1.5, -2), Point(3.5, -2), Point(3, 0), Point(6, 0), Point(6, 4),
                  Point(0, 4)},
                 {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle,
                  E::kObstacle}};
  const mapping::TypedMultiPolygon map{typed_polygon(outer)};
  auto chains = frontier_chains(map);
  ASSERT_EQ(chains.size(), 2u);
  find_walled_bays(map, chains, bays_below(1000.0));
  EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
  EXPECT_TRUE(std::isinf(chains[1].bay_area_m2));
}

TEST(WalledBays, AWallStretchNothingStandsInFrontOfIsNoBay) {
  // The wall between x 2 and 3 was not seen (a grazing look; a door may be
  // there): a shallow notch of frontier, and of wall 0.1 m in front of the
  // wall's line (scan noise), not an object in front of it.
  RingSpec outer{{Point(0, 0), Point(2, 0), Point(2.4, 0.1), Point(2.8, 0.1), Point(3, 0), Point(6, 0), Point(6, 4),
                  Point(0, 4)},
                 {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle,
                  E::kObstacle}};
  const mapping::TypedMultiPolygon map{typed_polygon(outer)};
  auto chains = frontier_chains(map);
  ASSERT_EQ(chains.size(), 2u);
  find_walled_bays(map, chains, bays_below(2.0));
  EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
  EXPECT_TRUE(std::isinf(chains[1].bay_area_m2));
  // Asked for less depth, the same notch is a bay: the depth is what rules it out.
  WalledBayOptions shallow = bays_below(2.0);
  shallow.min_depth_m = 0.05;
  find_walled_bays(map, chains, shallow);
  EXPECT_NEAR(chains[0].bay_area_m2, 0.07, 1e-9);
  EXPECT_NEAR(chains[1].bay_area_m2, 0.07, 1e-9);
}

TEST(WalledBays, WallsThatDoNotContinueAlongTheLidCloseNoBay) {
  // The desk's right flank meets the room's right wall instead of the bottom
  // wall: from (2, 0) the next wall edge runs up (x = 6), not along the lid.
  RingSpec outer{{Point(0, 0), Point(2, 0), Point(2, 0.85), Point(6, 0.85), Point(6, 4), Point(0, 4)},
                 {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle}};
  const mapping::TypedMultiPolygon map{typed_polygon(outer)};
  auto chains = frontier_chains(map);
  ASSERT_EQ(chains.size(), 1u);
  find_walled_bays(map, chains, bays_below(1000.0));
  EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
}

TEST(WalledBays, ALidThroughAnotherPieceOfTheMapIsNone) {
  // Free space seen behind the desk, across the wall's line (a room beyond a
  // gap: a second polygon of the map, x 2.5..3.1): the lid would cross it.
  auto map = room_with_a_desk_against_the_wall();
  map.push_back(typed_polygon(testing::rectangle(2.5, -1.0, 3.1, 0.02,
                                                 {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle})));
  auto chains = frontier_chains(map);
  find_walled_bays(map, chains, bays_below(2.0));
  EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
  EXPECT_TRUE(std::isinf(chains[1].bay_area_m2));
  // A sliver (under min_piece_m2) seen into the strip behind the desk does not.
  map.back() = typed_polygon(testing::rectangle(2.5, -0.02, 3.1, 0.02,
                                                {E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle}));
  chains = frontier_chains(map);
  find_walled_bays(map, chains, bays_below(2.0));
  EXPECT_NEAR(chains[0].bay_area_m2, 1.6 * 0.85, 1e-9);
}

TEST(WalledBays, NoLidTurnsACorner) {
  // A desk in the room's bottom-right corner (x 4.3..5.95): its bay would be
  // closed by the corner (6, 0). But so would, through a door, part of the
  // next room: the room's left wall carried on down and the far wall the
  // laser saw through the door, meeting at (0, -1) (2.75 m2 of unknown
  // beside the door's wedge). Neither is a bay: lids are straight.
  RingSpec desk{{Point(0, 0), Point(4.3, 0), Point(4.3, 0.85), Point(5.95, 0.85), Point(5.95, 1.0), Point(6, 1.0),
                 Point(6, 4), Point(0, 4)},
                {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle,
                 E::kObstacle}};
  RingSpec door{{Point(0, 0), Point(2, 0), Point(1.75, -1), Point(3.25, -1), Point(3, 0), Point(6, 0), Point(6, 4),
                 Point(0, 4)},
                {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle,
                 E::kObstacle}};
  for (const RingSpec& ring : {desk, door}) {
    const mapping::TypedMultiPolygon map{typed_polygon(ring)};
    auto chains = frontier_chains(map);
    ASSERT_EQ(chains.size(), 2u);
    find_walled_bays(map, chains, bays_below(3.0));
    EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
    EXPECT_TRUE(std::isinf(chains[1].bay_area_m2));
  }
}

TEST(WalledBays, ADeskInARoomsCornerLiesInABayAlongTheFarWallToTheSideWall) {
  // A desk 0.3 m from the room's right wall (x 4.3..5.7, 5 cm off the far
  // wall): the laser saw the far wall up to the desk and the right wall down
  // to the far wall's line, not the desk's left flank nor the corner behind
  // it. The lid runs along the far wall's line from (4.3, 0) to the right
  // wall's end (6, 0.02), which turns up into the room there.
  RingSpec corner{{Point(0, 0), Point(4.3, 0), Point(4.3, 0.85), Point(5.7, 0.85), Point(6, 0.02), Point(6, 4),
                   Point(0, 4)},
                  {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle}};
  mapping::TypedMultiPolygon map{typed_polygon(corner)};
  auto chains = frontier_chains(map);
  ASSERT_EQ(chains.size(), 2u);
  find_walled_bays(map, chains, bays_below(3.0));
  // The desk, the strip behind it and the corner beside it: the loop
  // (4.3, 0), (4.3, 0.85), (5.7, 0.85), (6, 0.02), 1.3035 m2.
  EXPECT_NEAR(chains[0].bay_area_m2, 1.3035, 1e-9);
  EXPECT_NEAR(chains[1].bay_area_m2, chains[0].bay_area_m2, 1e-12);
  // Mirrored (the desk in the left corner, the lid from the left wall's end
  // to the far wall beyond the desk): the same.
  mapping::TypedMultiPolygon mirrored{typed_polygon(
      RingSpec{{Point(0, 0.02), Point(0.3, 0.85), Point(1.7, 0.85), Point(1.7, 0), Point(6, 0), Point(6, 4), Point(0, 4)},
               {E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle}})};
  chains = frontier_chains(mirrored);
  ASSERT_EQ(chains.size(), 2u);
  find_walled_bays(mirrored, chains, bays_below(3.0));
  EXPECT_NEAR(chains[0].bay_area_m2, 1.3035, 1e-9);
  EXPECT_NEAR(chains[1].bay_area_m2, 1.3035, 1e-9);
  // The side wall's end 0.2 m off the far wall's line: not the corner.
  map[0].geometry.outer()[4] = Point(6, 0.2);
  chains = frontier_chains(map);
  find_walled_bays(map, chains, bays_below(3.0));
  EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
  // The wall at the lid's end turning away from the room (the free space
  // goes on past the corner: a passage), not into it: no bay.
  RingSpec passage{{Point(0, 0), Point(4.3, 0), Point(4.3, 0.85), Point(5.7, 0.85), Point(6, 0.02), Point(6, -3),
                    Point(8, -3), Point(8, 4), Point(0, 4)},
                   {E::kObstacle, E::kFrontier, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kObstacle,
                    E::kObstacle, E::kObstacle}};
  const mapping::TypedMultiPolygon open_map{typed_polygon(passage)};
  chains = frontier_chains(open_map);
  find_walled_bays(open_map, chains, bays_below(3.0));
  EXPECT_TRUE(std::isinf(chains[0].bay_area_m2));
}

TEST(WalledBays, AMapOfManyTinyEdgesIsReadWithinABudgetNeverTakenAsABay) {
  // The desk's room, its ring starting at (0, 4) and its left wall a zigzag
  // of 40,000 edges 0.1 mm long, every other one frontier: 20,000 chains,
  // each walking up to 8 m of ring before the desk's two come. The ring
  // steps have a budget linear in the map's size; past it the desk's chains
  // are not looked at and stay goals (+inf), never the other way round.
  auto room = [](int zigzag_edges) {
    std::vector<Point> points{Point(0, 4)};
    std::vector<E> types;
    for (int i = 1; i <= zigzag_edges; ++i) {
      points.push_back(Point(i % 2 == 1 && i < zigzag_edges ? 1e-4 : 0.0, 4.0 - 4.0 * i / zigzag_edges));
      types.push_back(i % 2 == 1 ? E::kFrontier : E::kObstacle);
    }
    for (const Point& p : {Point(2, 0), Point(2, 0.85), Point(3.6, 0.85), Point(3.6, 0.05), Point(3.6, 0), Point(6, 0),
                           Point(6, 4)})
      points.push_back(p);
    for (E t : {E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle,
                E::kObstacle})
      types.push_back(t);
    return mapping::TypedMultiPolygon{typed_polygon(RingSpec{points, types})};
  };
  auto desk_bays = [](const mapping::TypedMultiPolygon& map) {
    auto chains = frontier_chains(map);
    find_walled_bays(map, chains, bays_below(2.0));
    std::vector<double> areas;
    for (const auto& c : chains)
      if (c.points.front().y() < 1.0 && c.points.front().x() > 1.0) areas.push_back(c.bay_area_m2);
    return areas;
  };
  const auto few = desk_bays(room(2));
  ASSERT_EQ(few.size(), 2u);
  EXPECT_NEAR(few[0], 1.6 * 0.85, 1e-9);
  const auto many = desk_bays(room(40000));
  ASSERT_EQ(many.size(), 2u);
  EXPECT_TRUE(std::isinf(many[0]));
  EXPECT_TRUE(std::isinf(many[1]));
}

TEST(WalledBays, AChainOnAHoleRingFindsItsBayToo) {
  // The room as a hole of a larger map polygon would be built clockwise: the
  // same desk on the wall of a courtyard seen from outside (a hole whose
  // ring has free space on its left as well).
  RingSpec outer{{Point(-10, -10), Point(20, -10), Point(20, 20), Point(-10, 20)},
                 {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle}};
  // A 6 x 4 m block (the hole) whose top wall (y = 4, seen from above) has a
  // desk in front of it on the free side, x 2..3.6, front at y = 4.85.
  RingSpec hole{{Point(0, 0), Point(0, 4), Point(2, 4), Point(2, 4.85), Point(3.6, 4.85), Point(3.6, 4),
                 Point(6, 4), Point(6, 0)},
                {E::kObstacle, E::kObstacle, E::kObstacle, E::kObstacle, E::kFrontier, E::kObstacle, E::kObstacle,
                 E::kObstacle}};
  const mapping::TypedMultiPolygon map{typed_polygon(outer, {hole})};
  auto chains = frontier_chains(map);
  ASSERT_EQ(chains.size(), 1u);
  find_walled_bays(map, chains, bays_below(2.0));
  EXPECT_NEAR(chains[0].bay_area_m2, 1.6 * 0.85, 1e-9);
}

}  // namespace
}  // namespace pex::planning
