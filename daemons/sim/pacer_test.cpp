#include "pacer.hpp"

#include <gtest/gtest.h>

namespace pex::simd {
namespace {

TEST(Pacer, HoldsTheClockWhileAChannelLagsAndLetsGoWhenItCatchesUp) {
  Pacer p(PacingOptions{{"SLAM_POSE", "BASE_CMD"}, {}, 150'000, 2.0});
  EXPECT_TRUE(p.may_advance(1'000'000, 0.0));  // nothing heard yet: nothing to wait for
  p.on_stamp(0, 1'000'000, 0.0);
  p.on_stamp(1, 1'000'000, 0.0);
  EXPECT_TRUE(p.may_advance(1'150'000, 0.1));
  EXPECT_FALSE(p.may_advance(1'150'001, 0.1));
  EXPECT_EQ(p.holding(1'200'000, 0.1), "SLAM_POSE");
  p.on_stamp(0, 1'100'000, 0.2);
  EXPECT_EQ(p.holding(1'200'000, 0.2), "BASE_CMD");
  p.on_stamp(1, 1'190'000, 0.2);
  EXPECT_TRUE(p.may_advance(1'200'000, 0.2));
}

TEST(Pacer, ASilentChannelStopsHoldingAfterItsWallTimeAndHoldsAgainWhenHeard) {
  Pacer p(PacingOptions{{"SLAM_POSE"}, {}, 150'000, 2.0});
  p.on_stamp(0, 1'000'000, 10.0);
  EXPECT_FALSE(p.may_advance(2'000'000, 11.9));
  EXPECT_TRUE(p.may_advance(2'000'000, 12.1));  // slam died: the world goes on
  p.on_stamp(0, 900'000, 20.0);                 // restarted; a stamp never moves back
  EXPECT_FALSE(p.may_advance(2'000'000, 20.0));
  p.on_stamp(0, 1'950'000, 20.5);
  EXPECT_TRUE(p.may_advance(2'000'000, 20.5));
}

TEST(Pacer, AChannelMayLagByItsPeriodMore) {
  // MAP at 1 Hz: a second old while the mapper keeps up.
  Pacer p(PacingOptions{{"BASE_CMD", "MAP"}, {100'000, 1'000'000}, 150'000, 2.0});
  p.on_stamp(0, 10'000'000, 0.0);
  p.on_stamp(1, 9'000'000, 0.0);
  EXPECT_TRUE(p.may_advance(10'150'000, 0.0));
  EXPECT_FALSE(p.may_advance(10'150'001, 0.0));
  EXPECT_EQ(p.holding(10'150'001, 0.0), "MAP");
  p.on_stamp(1, 10'000'000, 0.1);
  EXPECT_TRUE(p.may_advance(10'250'000, 0.1));
  EXPECT_EQ(p.holding(10'250'001, 0.1), "BASE_CMD");
}

TEST(Pacer, ZeroLagIsOff) {
  Pacer p(PacingOptions{{"SLAM_POSE"}, {}, 0, 2.0});
  p.on_stamp(0, 0, 0.0);
  EXPECT_TRUE(p.may_advance(100'000'000, 0.0));
}

}  // namespace
}  // namespace pex::simd
