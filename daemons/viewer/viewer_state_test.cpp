// ViewerState: messages in, the page's JSON out; bad messages refused with
// the last good state kept.
#include "viewer_state.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace pex::viewer {
namespace {

pex::polygon_ring_t ring(std::vector<double> x, std::vector<double> y, std::vector<std::int8_t> types,
                         bool hole = false, int polygon = 0) {
  pex::polygon_ring_t r{};
  r.polygon = polygon;
  r.hole = hole;
  r.nvertices = static_cast<int>(x.size());
  r.x = std::move(x);
  r.y = std::move(y);
  r.edge_type = std::move(types);
  return r;
}

// A 4 x 3 m room with a 1 x 1 m pillar; its right edge is a frontier.
pex::polygon_map_t room_map() {
  pex::polygon_map_t m{};
  m.utime = 7;
  m.rings.push_back(ring({0, 4, 4, 0}, {0, 0, 3, 3}, {0, 1, 0, 0}));
  m.rings.push_back(ring({1, 1, 2, 2}, {1, 2, 2, 1}, {0, 0, 0, 0}, true));
  m.nrings = 2;
  m.vertex_count = 8;
  m.free_area_m2 = 11.0;
  return m;
}

pex::pose_t pose(double x, double y, double theta) {
  pex::pose_t p{};
  p.x = x;
  p.y = y;
  p.theta = theta;
  return p;
}

TEST(ViewerState, MapJsonHasEveryRingWithItsEdgeTypes) {
  ViewerState s;
  EXPECT_EQ(s.map_version(), 0);
  EXPECT_NO_THROW(s.on_map(room_map()));
  EXPECT_EQ(s.map_version(), 1);
  const auto j = s.map_json();
  ASSERT_EQ(j["rings"].size(), 2u);
  EXPECT_EQ(j["frame"], "map");
  EXPECT_EQ(j["rings"][0]["x"], nlohmann::json({0, 4, 4, 0}));
  EXPECT_EQ(j["rings"][0]["edge_type"], nlohmann::json({0, 1, 0, 0}));
  EXPECT_EQ(j["rings"][1]["hole"], true);
  EXPECT_DOUBLE_EQ(j["free_area_m2"].get<double>(), 11.0);
}

TEST(ViewerState, ABadMapIsRefusedAndTheLastGoodOneKept) {
  ViewerState s;
  ASSERT_NO_THROW(s.on_map(room_map()));
  auto bad = room_map();
  bad.rings[0].x[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(s.on_map(bad), std::invalid_argument);
  auto sizes = room_map();
  sizes.rings[1].edge_type.pop_back();
  EXPECT_THROW(s.on_map(sizes), std::invalid_argument);
  auto count = room_map();
  count.nrings = 5;
  EXPECT_THROW(s.on_map(count), std::invalid_argument);
  auto type = room_map();
  type.rings[0].edge_type[0] = 7;
  EXPECT_THROW(s.on_map(type), std::invalid_argument);
  EXPECT_EQ(s.map_version(), 1);
  EXPECT_EQ(s.map_json()["rings"][0]["x"], nlohmann::json({0, 4, 4, 0}));

  ViewerState small({.max_map_vertices = 7});
  EXPECT_THROW(small.on_map(room_map()), std::invalid_argument);  // 8 vertices
}

// KEEP_OUT: the explorer's keep-out drawn with the map, before a map too; the
// same one again (every 5 s) leaves the map's version, a new one bumps it; a
// bad one is refused and the last good one kept.
TEST(ViewerState, KeepOutIsShownWithTheMapAndABadOneRefused) {
  ViewerState s;
  EXPECT_TRUE(s.map_json()["keep_out"].is_null());
  pex::polygon_map_t strip{};
  strip.utime = 9;
  strip.particle = -1;
  strip.rings.push_back(ring({3.975, 4.025, 4.025, 3.975}, {0, 0, 1.5, 1.5}, {0, 0, 0, 0}));
  strip.nrings = 1;
  EXPECT_NO_THROW(s.on_keep_out(strip));
  EXPECT_EQ(s.map_version(), 1);
  auto j = s.map_json();
  ASSERT_EQ(j["keep_out"]["rings"].size(), 1u);
  EXPECT_EQ(j["keep_out"]["rings"][0]["x"], nlohmann::json({3.975, 4.025, 4.025, 3.975}));
  EXPECT_EQ(j["keep_out"]["utime"], 9);
  EXPECT_FALSE(j.contains("rings"));  // no map yet

  EXPECT_NO_THROW(s.on_map(room_map()));
  strip.utime = 10;
  EXPECT_NO_THROW(s.on_keep_out(strip));  // unchanged
  EXPECT_EQ(s.map_version(), 2);
  j = s.map_json();
  EXPECT_EQ(j["rings"].size(), 2u);
  EXPECT_EQ(j["keep_out"]["rings"].size(), 1u);

  auto bad = strip;
  bad.rings[0].x[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(s.on_keep_out(bad), std::invalid_argument);
  auto far = strip;
  far.rings[0].x[1] = 5e6;
  EXPECT_THROW(s.on_keep_out(far), std::invalid_argument);
  EXPECT_EQ(s.map_version(), 2);
  EXPECT_EQ(s.map_json()["keep_out"]["rings"][0]["x"][1], 4.025);

  auto moved = strip;
  moved.rings[0].y[2] = 2.0;
  EXPECT_NO_THROW(s.on_keep_out(moved));
  EXPECT_EQ(s.map_version(), 3);
  EXPECT_EQ(s.live_json(0)["counts"]["keep_outs"], 3);
}

TEST(ViewerState, TrajectoryGrowsWithMotionAndIsThinnedBeyondItsLimit) {
  ViewerState s({.trajectory_min_step_m = 0.1, .max_trajectory_points = 10});
  EXPECT_NO_THROW(s.on_pose(pose(0, 0, 0)));
  EXPECT_NO_THROW(s.on_pose(pose(0.05, 0, 0)));  // too close: same point
  EXPECT_EQ(s.trajectory().size(), 1u);
  for (int i = 1; i <= 20; ++i) ASSERT_NO_THROW(s.on_pose(pose(0.2 * i, 0, 0)));
  EXPECT_LE(s.trajectory().size(), 10u);
  EXPECT_GE(s.trajectory().size(), 5u);
  EXPECT_DOUBLE_EQ(s.trajectory().back().first, 4.0);  // the newest point stays
  EXPECT_THROW(s.on_pose(pose(std::numeric_limits<double>::infinity(), 0, 0)), std::invalid_argument);
  const auto live = s.live_json(0);
  EXPECT_DOUBLE_EQ(live["pose"]["x"].get<double>(), 4.0);
}

TEST(ViewerState, ScanPointsAreInTheMapFrameFromTheNewestPose) {
  ViewerState s;
  pex::laser_scan_t scan{};
  scan.angle_min = 0.0f;
  scan.angle_increment = static_cast<float>(M_PI / 2);
  scan.range_min = 0.1f;
  scan.range_max = 10.0f;
  scan.sensor_x = 0.1f;
  scan.ranges = {1.0f, 2.0f, 50.0f};  // ahead, left, no return
  scan.nranges = 3;
  EXPECT_NO_THROW(s.on_scan(scan));  // no pose yet: nothing to draw, nothing wrong
  EXPECT_TRUE(s.live_json(0)["scan"].is_null());
  ASSERT_NO_THROW(s.on_pose(pose(1.0, 2.0, M_PI / 2)));
  ASSERT_NO_THROW(s.on_scan(scan));
  const auto points = s.live_json(0)["scan"]["points"];
  ASSERT_EQ(points.size(), 2u);
  // Sensor at (1, 2.1) facing +y: 1 m ahead is (1, 3.1); 2 m to its left is (-1, 2.1).
  EXPECT_NEAR(points[0][0].get<double>(), 1.0, 1e-3);
  EXPECT_NEAR(points[0][1].get<double>(), 3.1, 1e-3);
  EXPECT_NEAR(points[1][0].get<double>(), -1.0, 1e-3);
  EXPECT_NEAR(points[1][1].get<double>(), 2.1, 1e-3);
  scan.nranges = 4;  // disagrees with the array
  EXPECT_THROW(s.on_scan(scan), std::invalid_argument);
  EXPECT_EQ(s.live_json(0)["scan"]["points"].size(), 2u);
}

TEST(ViewerState, MissionShowsPhaseGoalPathAndFrontiers) {
  ViewerState s;
  EXPECT_TRUE(s.live_json(0)["mission"].is_null());
  pex::explore_state_t e{};
  e.phase = pex::explore_state_t::PHASE_MOVING;
  e.status = "to goal 3";
  e.has_goal = true;
  e.goal_x = 3.0;
  e.goal_y = 1.5;
  e.npath = 2;
  e.path_x = {0.0, 3.0};
  e.path_y = {0.0, 1.5};
  e.nfrontiers = 1;
  e.frontier_x = {5.0};
  e.frontier_y = {1.0};
  e.frontier_reason = {std::int8_t{pex::explore_state_t::FRONTIER_NO_PATH}};
  e.explored_area_m2 = 12.5;
  ASSERT_NO_THROW(s.on_explore_state(e));
  auto m = s.live_json(0)["mission"];
  EXPECT_EQ(m["phase_name"], "MOVING");
  EXPECT_EQ(m["goal"]["x"], 3.0);
  EXPECT_EQ(m["path"], nlohmann::json({{0.0, 0.0}, {3.0, 1.5}}));
  EXPECT_EQ(m["frontiers"][0]["reason"], int{pex::explore_state_t::FRONTIER_NO_PATH});
  EXPECT_EQ(m["explored_area_m2"], 12.5);

  auto bad = e;
  bad.phase = pex::explore_state_t::PHASE_PAUSED;
  bad.path_y.pop_back();
  EXPECT_THROW(s.on_explore_state(bad), std::invalid_argument);
  EXPECT_EQ(s.live_json(0)["mission"]["phase_name"], "MOVING");
  EXPECT_STREQ(phase_name(pex::explore_state_t::PHASE_PAUSED), "PAUSED");
  EXPECT_STREQ(phase_name(99), "UNKNOWN");
}

TEST(ViewerState, HealthTableSortedByNameWithStaleDaemonsMarked) {
  ViewerState s({.status_stale_s = 3.0});
  pex::daemon_status_t st{};
  st.name = "slam";
  st.state = pex::daemon_status_t::STATE_OK;
  ASSERT_NO_THROW(s.on_status(st, 1'000'000));
  st.name = "explorer";
  st.state = pex::daemon_status_t::STATE_DEGRADED;
  st.last_error = "no laser scans";
  ASSERT_NO_THROW(s.on_status(st, 3'000'000));
  st.ncounters = 1;  // no names, no values
  EXPECT_THROW(s.on_status(st, 3'000'000), std::invalid_argument);
  const auto d = s.live_json(5'000'000)["daemons"];
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0]["name"], "explorer");
  EXPECT_EQ(d[0]["state_name"], "DEGRADED");
  EXPECT_EQ(d[0]["stale"], false);  // 2 s ago
  EXPECT_EQ(d[1]["name"], "slam");
  EXPECT_EQ(d[1]["stale"], true);  // 4 s ago
  EXPECT_DOUBLE_EQ(d[1]["age_s"].get<double>(), 4.0);
}

TEST(ViewerState, StateJsonIsTheLiveStateWithTheMap) {
  ViewerState s;
  ASSERT_NO_THROW(s.on_map(room_map()));
  ASSERT_NO_THROW(s.on_pose(pose(1, 1, 0)));
  const auto j = s.state_json(42);
  EXPECT_EQ(j["utime"], 42);
  EXPECT_EQ(j["map"]["rings"].size(), 2u);
  EXPECT_EQ(j["map_version"], 1);
  EXPECT_EQ(j["counts"]["maps"], 1);
  // One line: a server-sent event's data must not hold a newline.
  EXPECT_EQ(j.dump().find('\n'), std::string::npos);
}

}  // namespace
}  // namespace pex::viewer
