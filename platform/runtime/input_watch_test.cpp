#include "runtime/input_watch.hpp"

#include <gtest/gtest.h>

using pex::runtime::InputWatch;

TEST(InputWatch, NamesTheFirstInputThatWentQuiet) {
  InputWatch w;
  w.expect("LIDAR_SCAN", 2'000'000);
  w.expect("ODOMETRY", 1'000'000);
  EXPECT_EQ(w.stale(10'000'000), "");            // the clock starts here
  EXPECT_EQ(w.stale(11'500'000), "no ODOMETRY yet");  // 1.5 s without any
  w.seen("ODOMETRY", 11'600'000);
  EXPECT_EQ(w.stale(11'700'000), "");
  EXPECT_EQ(w.stale(12'100'000), "no LIDAR_SCAN yet");
  w.seen("LIDAR_SCAN", 12'200'000);
  EXPECT_EQ(w.stale(12'500'000), "");
  EXPECT_EQ(w.stale(12'700'000), "no ODOMETRY for 1.1 s");
  w.seen("ODOMETRY", 12'800'000);
  EXPECT_EQ(w.stale(13'900'000), "no ODOMETRY for 1.1 s");
  w.seen("ODOMETRY", 13'900'000);
  EXPECT_EQ(w.stale(14'300'000), "no LIDAR_SCAN for 2.1 s");  // the first one registered is named first
  w.seen("LIDAR_SCAN", 14'300'000);
  EXPECT_EQ(w.stale(14'300'000), "");
  w.seen("UNKNOWN", 14'400'000);  // not watched: nothing changes
  EXPECT_EQ(w.stale(14'400'000), "");
}
