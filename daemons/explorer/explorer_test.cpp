// The explorer daemon's adapter: MAP decoding, options, the node without a bus.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <tuple>

#include "explorer_node.hpp"
#include "explorer_options.hpp"
#include "map_message.hpp"
#include "mapping/test_support.hpp"
#include "runtime/config.hpp"
#include "runtime/daemon.hpp"

namespace pex::explorer {
namespace {

using mapping::EdgeType;
using mapping::Point;

pex::polygon_ring_t ring(std::int32_t polygon, bool hole, const std::vector<std::pair<double, double>>& pts,
                         std::vector<std::int8_t> types = {}) {
  pex::polygon_ring_t r{};
  r.polygon = polygon;
  r.hole = hole;
  for (const auto& [x, y] : pts) {
    r.x.push_back(x);
    r.y.push_back(y);
  }
  r.edge_type = types.empty() ? std::vector<std::int8_t>(pts.size(), std::int8_t{0}) : types;
  r.nvertices = static_cast<std::int32_t>(pts.size());
  return r;
}

pex::polygon_map_t map_of(std::vector<pex::polygon_ring_t> rings) {
  pex::polygon_map_t m{};
  m.rings = std::move(rings);
  m.nrings = static_cast<std::int32_t>(m.rings.size());
  return m;
}

// A 20 x 3 m corridor with a frontier at its right end (edge 1).
pex::polygon_map_t corridor() {
  return map_of({ring(0, false, {{0, 0}, {20, 0}, {20, 3}, {0, 3}}, {0, 1, 0, 0})});
}

// The robot in the corridor's middle (10, 1.5), facing along it toward the frontier.
pex::pose_t mid_corridor() {
  pex::pose_t pose{};
  pose.x = 10;
  pose.y = 1.5;
  return pose;
}

TEST(DecodeMap, RoomWithAHole) {
  const auto d = decode_map(map_of({ring(7, false, {{0, 0}, {10, 0}, {10, 10}, {0, 10}}),
                                    ring(7, true, {{4, 4}, {4, 6}, {6, 6}, {6, 4}}, {1, 1, 1, 1})}));
  ASSERT_TRUE(d.ok) << d.error;
  ASSERT_EQ(d.polygons.size(), 1u);
  EXPECT_NEAR(mapping::area(d.polygons), 96.0, 1e-12);
  EXPECT_NEAR(mapping::edge_length(d.polygons, EdgeType::kFrontier), 8.0, 1e-12);
  EXPECT_EQ(d.rings_reoriented, 0);
}

TEST(DecodeMap, ReversesARingGivenClockwiseWithItsTypes) {
  // The corridor clockwise: (0,0) (0,3) (20,3) (20,0); the frontier edge is
  // (20,3) -> (20,0), entry 2.
  const auto d = decode_map(map_of({ring(0, false, {{0, 0}, {0, 3}, {20, 3}, {20, 0}}, {0, 0, 1, 0})}));
  ASSERT_TRUE(d.ok) << d.error;
  EXPECT_EQ(d.rings_reoriented, 1);
  int frontier_edges = 0;
  mapping::for_each_edge(d.polygons, [&](const Point& a, const Point& b, EdgeType t) {
    if (t != EdgeType::kFrontier) return;
    ++frontier_edges;
    EXPECT_EQ(a.x(), 20.0);
    EXPECT_EQ(b.x(), 20.0);
    EXPECT_LT(a.y(), b.y());  // counter-clockwise now: up the right side
  });
  EXPECT_EQ(frontier_edges, 1);
}

TEST(DecodeMap, RefusesBadMessagesAndDropsBrokenPolygons) {
  auto nan = corridor();
  nan.rings[0].x[1] = std::nan("");
  EXPECT_FALSE(decode_map(nan).ok);
  // Finite but absurd (issue 12; the fuzz target map_message asserts the bound).
  auto far = corridor();
  far.rings[0].x[1] = 1e300;
  EXPECT_NE(decode_map(far).error.find("beyond"), std::string::npos);
  far.rings[0].x[1] = -2e6;
  EXPECT_FALSE(decode_map(far).ok);
  auto bad_type = corridor();
  bad_type.rings[0].edge_type[0] = 5;
  EXPECT_NE(decode_map(bad_type).error.find("edge type"), std::string::npos);
  auto count = corridor();
  count.nrings = 3;
  EXPECT_FALSE(decode_map(count).ok);
  auto sizes = corridor();
  sizes.rings[0].y.pop_back();
  EXPECT_FALSE(decode_map(sizes).ok);
  MapDecodeOptions small;
  small.max_vertices = 3;
  EXPECT_NE(decode_map(corridor(), small).error.find("limit"), std::string::npos);
  // A bow-tie polygon beside a good one: the bow-tie goes, the room stays.
  const auto mixed = decode_map(map_of({ring(0, false, {{0, 0}, {10, 0}, {10, 10}, {0, 10}}),
                                        ring(1, false, {{20, 0}, {22, 2}, {22, 0}, {20, 2}})}));
  ASSERT_TRUE(mixed.ok) << mixed.error;
  EXPECT_EQ(mixed.polygons.size(), 1u);
  EXPECT_EQ(mixed.polygons_dropped, 1);
  // Only broken polygons: refused.
  EXPECT_FALSE(decode_map(map_of({ring(1, false, {{20, 0}, {22, 2}, {22, 0}, {20, 2}})})).ok);
  // An empty map is a map (nothing seen yet).
  EXPECT_TRUE(decode_map(map_of({})).ok);
}

TEST(DecodeMap, EncodeDecodeRoundTrip) {
  const auto first = decode_map(corridor());
  ASSERT_TRUE(first.ok);
  const auto again = decode_map(encode_map(first.polygons, 1));
  ASSERT_TRUE(again.ok);
  ASSERT_EQ(again.polygons.size(), 1u);
  EXPECT_EQ(again.polygons[0].edge_types, first.polygons[0].edge_types);
  EXPECT_TRUE(boost::geometry::equals(again.polygons[0].geometry, first.polygons[0].geometry));
}

TEST(ExplorerOptions, ShippedConfigsLoadAndEveryKeyIsRead) {
  const std::string sim = std::string(PEX_SOURCE_DIR) + "/config/explorer.toml";
  const std::string robot = std::string(PEX_SOURCE_DIR) + "/config/robot/explorer.toml";  // the robot's overlay
  for (const std::vector<std::string>& files : {std::vector<std::string>{sim}, std::vector<std::string>{sim, robot}}) {
    auto config = runtime::ConfigReader::from_files(files);
    const auto runtime_options = runtime::load_runtime_options(config);  // read by run_daemon
    const auto o = load_options(config);
    EXPECT_NO_THROW(config.finish()) << files.back();
    EXPECT_EQ(o.pose_channel, "SLAM_POSE");
    EXPECT_EQ(o.mission.planner.cspace.robot_radius_m, 0.27);
    // The simulator's set explores at once on the sim's clock; a robot that
    // boots waits for a start command and runs on the system clock.
    const bool on_robot = files.size() == 2;
    EXPECT_EQ(o.mission.autostart, !on_robot) << files.back();
    EXPECT_EQ(runtime_options.clock, on_robot ? runtime::ClockSource::kSystem : runtime::ClockSource::kSim) << files.back();
    EXPECT_EQ(o.mission.scan_timeout_us, 500'000) << files.back();  // no driving blind, on the robot too
    // A way in keeps half the margin (docs/exploration.md, "Frontiers seen through a door").
    EXPECT_EQ(o.mission.way_in_margin_m, 0.025) << files.back();
    EXPECT_EQ(o.mission.planner.cspace.clearance_margin_m, 0.05) << files.back();
    EXPECT_EQ(o.mission.planner.trail_corridor_m, 0.05) << files.back();  // tight plans go along the trail
    // The guard reads wall ends and corners, on the robot too ("Scan guard").
    EXPECT_EQ(o.guard.body_radius_m, 0.25) << files.back();
    EXPECT_EQ(o.guard_scan.wall_end_reach_m, 0.03) << files.back();
    EXPECT_EQ(o.guard_scan.wall_end_jump_m, 0.07) << files.back();
    // No live view in the plans: through glass at a slant it reopened the
    // panes ("Glass: the live view"); a guard hold replans ("Held by the guard").
    EXPECT_EQ(o.live_view.range_m, 0.0) << files.back();
    EXPECT_TRUE(o.live_view_when_stuck_only) << files.back();
    EXPECT_EQ(o.guard_block_us, 1'000'000) << files.back();
    EXPECT_EQ(o.mission.max_guard_blocks_per_goal, 8) << files.back();
    // What held the robot is kept out of the plans ("Guard marks").
    EXPECT_EQ(o.guard_marks.lifetime_s, 300.0) << files.back();
    EXPECT_EQ(o.guard_marks.holding_depth_m, 0.10) << files.back();
    EXPECT_EQ(o.guard_marks.max_reach_m, 0.5) << files.back();
    EXPECT_EQ(o.guard_marks.width_m, 0.05) << files.back();
    EXPECT_EQ(o.guard_marks.max_marks, 32) << files.back();
  }
}

TEST(ExplorerOptions, RejectsBadValues) {
  for (const char* text : {"pose_channel = \"MAP\"", "robot_radius_m = -1.0", "max_speed_mps = 0.0",
                           "guard_mark_lifetime_s = -1.0", "max_guard_marks = -1", "guard_mark_width_m = 0.0",
                           "turn_in_place_rad = 0.2\nturn_in_place_exit_rad = 0.5",
                           "robot_radius_m = 1.5\ncandidate_snap_distance_m = 1.0",
                           "robot_radius_m = 0.3\nreach_past_frontier_m = 0.3", "reach_past_frontier_m = -0.01",
                           "way_in_margin_m = -0.01", "trail_corridor_m = -0.01", "trail_corridor_m = 0.6",
                           "guard_wall_end_reach_m = -0.01", "guard_wall_end_reach_m = 0.6",
                           "guard_wall_end_jump_m = 0.0"}) {
    auto config = runtime::ConfigReader::from_string(text, "test.toml");
    EXPECT_THROW(load_options(config), runtime::ConfigError) << text;
  }
  auto strategy = runtime::ConfigReader::from_string("goal_strategy = \"nearest\"", "test.toml");
  EXPECT_THROW(load_options(strategy), runtime::ConfigError);
  auto sim = runtime::ConfigReader::from_string("pose_channel = \"SIM_TRUTH\"", "test.toml");
  EXPECT_EQ(load_options(sim).pose_channel, "SIM_TRUTH");
}

TEST(ExplorerOptions, KeepOutFileIsReadInTheMapFrameAndItsErrorsNameTheLine) {
  const std::string good = ::testing::TempDir() + "/keep_out_good.wkt";
  const std::string bad = ::testing::TempDir() + "/keep_out_bad.wkt";
  {
    std::ofstream(good) << "# glass\nLINESTRING (5 6, 9 6)\nPOLYGON ((0 0, 1 0, 1 1, 0 1, 0 0))\n";
    std::ofstream(bad) << "LINESTRING (5 6, 9 6)\nLINESTRING (5 6, nan 6)\n";
  }
  auto none = runtime::ConfigReader::from_string("", "test.toml");
  EXPECT_EQ(load_options(none).keep_out, nullptr);
  auto config = runtime::ConfigReader::from_string(
      "keep_out_file = \"" + good + "\"\nkeep_out_start_pose_m_m_rad = [5.0, 5.0, 0.0]\n", "test.toml");
  const auto o = load_options(config);
  ASSERT_NE(o.keep_out, nullptr);
  EXPECT_EQ(o.keep_out_lines, 1);
  EXPECT_EQ(o.keep_out_areas, 1);
  // The line (5 6, 9 6) with the robot starting at (5, 5): map (0, 1) .. (4, 1).
  bool covers_line = false;
  for (const auto& polygon : *o.keep_out)
    covers_line = covers_line || boost::geometry::covered_by(mapping::Point(2.0, 1.0), polygon.geometry);
  EXPECT_TRUE(covers_line);
  auto broken = runtime::ConfigReader::from_string("keep_out_file = \"" + bad + "\"\n", "test.toml");
  try {
    load_options(broken);
    ADD_FAILURE() << "a bad keep-out file was taken";
  } catch (const runtime::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(bad + ":2:"), std::string::npos) << e.what();
  }
  auto missing = runtime::ConfigReader::from_string("keep_out_file = \"/nonexistent/keep.wkt\"\n", "test.toml");
  EXPECT_THROW(load_options(missing), runtime::ConfigError);
  auto pose = runtime::ConfigReader::from_string("keep_out_start_pose_m_m_rad = [1.0, 2.0]\n", "test.toml");
  EXPECT_THROW(load_options(pose), runtime::ConfigError);
}

TEST(ExplorerNode, DrivesTowardTheFrontierAndStopsWhenThePoseIsStale) {
  ExplorerOptions options;
  ExplorerNode node(options);
  EXPECT_EQ(node.step(0).v, 0.0);
  EXPECT_EQ(node.state_message(0).phase, +pex::explore_state_t::PHASE_IDLE);

  const pex::pose_t pose = mid_corridor();
  ASSERT_NO_THROW(node.on_map(corridor(), 0));
  ASSERT_NO_THROW(node.on_pose(pose, 0));
  node.step(0);
  ASSERT_NO_THROW(node.on_pose(pose, 100'000));
  const auto cmd = node.step(100'000);
  EXPECT_GT(cmd.v, 0.0);
  EXPECT_EQ(cmd.source, "explorer");
  const auto state = node.state_message(100'000);
  EXPECT_EQ(state.phase, +pex::explore_state_t::PHASE_MOVING);
  EXPECT_GE(state.npath, 2);
  EXPECT_EQ(state.path_x.size(), static_cast<std::size_t>(state.npath));
  const auto& cs = options.mission.planner.cspace;
  EXPECT_NEAR(state.goal_x, 20.0 - cs.robot_radius_m - cs.clearance_margin_m, 0.01);
  EXPECT_EQ(state.goal_candidates, 1);
  EXPECT_NEAR(state.explored_area_m2, 60.0, 1e-9);

  const auto stale = node.step(2'000'000);  // no pose for 1.9 s
  EXPECT_EQ(stale.v, 0.0);
  EXPECT_EQ(stale.omega, 0.0);
  EXPECT_TRUE(node.last_output().degraded);
  EXPECT_NE(node.state_message(2'000'000).status.find("DEGRADED"), std::string::npos);

  pex::pose_t bad = pose;
  bad.theta = std::nan("");
  EXPECT_THROW(node.on_pose(bad, 2'100'000), std::invalid_argument);
  auto broken = corridor();
  broken.rings[0].edge_type[0] = 9;
  EXPECT_THROW(node.on_map(broken, 2'100'000), std::invalid_argument);
  EXPECT_EQ(node.counters().maps_accepted, 1);
}

// The explorer's DAEMON_STATUS values after its first plan on `map` from
// `pose` and after a replan on the same map from the same pose.
struct StatusTotals {
  std::map<std::string, std::int64_t> values;
  void total(const std::string& name, std::int64_t value) { values[name] = value; }
  std::int64_t at(const std::string& name) const { return values.at(name); }
};
std::pair<StatusTotals, StatusTotals> status_after_plan_and_replan(const ExplorerOptions& options,
                                                                   const pex::polygon_map_t& map, double x, double y) {
  ExplorerNode node(options);
  pex::pose_t pose{};
  pose.x = x;
  pose.y = y;
  node.on_map(map, 0);
  node.on_pose(pose, 0);
  node.step(0);
  StatusTotals first, second;
  node.visit_counters(first);
  const std::int64_t replan_us = options.mission.replan_period_us + 100'000;
  node.on_pose(pose, replan_us);
  node.step(replan_us);
  node.visit_counters(second);
  return {first, second};
}

// DAEMON_STATUS says how the C-space's offset was had: a replan on the map
// it planned on before takes its polygon from the planning thread's cache.
TEST(ExplorerNode, CountsOffsetTilesKeptAndComputed) {
  const auto [first, second] = status_after_plan_and_replan(ExplorerOptions{}, corridor(), 10, 1.5);
  EXPECT_EQ(first.at("offset_tiles_kept"), 0);
  EXPECT_GE(first.at("offset_tiles_computed"), 1);
  ASSERT_GT(second.at("plans"), first.at("plans"));
  EXPECT_GE(second.at("offset_tiles_kept"), 1);
  EXPECT_EQ(second.at("offset_tiles_computed"), first.at("offset_tiles_computed"));
}

// DAEMON_STATUS says how the tour's path graph was had: a replan on the same
// map from the same pose answers every segment test from the last graph.
TEST(ExplorerNode, CountsPathGraphTestsKeptAndNew) {
  ExplorerOptions options;
  options.mission.planner.strategy = planning::GoalStrategy::kTour;
  options.mission.planner.tour.horizon_candidates = 0;  // the whole matrix: the graph of every plan
  // A room with a block in it (its corners are the graph's reflex nodes), open at the east end.
  const auto room = map_of({ring(0, false, {{0, 0}, {20, 0}, {20, 10}, {0, 10}}, {0, 1, 0, 0}),
                            ring(0, true, {{8, 3}, {8, 7}, {12, 7}, {12, 3}})});
  const auto [first, second] = status_after_plan_and_replan(options, room, 2, 5);
  ASSERT_GE(first.at("plans"), 1);
  EXPECT_EQ(first.at("graph_tests_kept"), 0);
  EXPECT_GE(first.at("graph_tests_new"), 1);
  ASSERT_GT(second.at("plans"), first.at("plans"));
  EXPECT_EQ(second.at("graph_tests_kept"), first.at("graph_tests_new"));
  EXPECT_EQ(second.at("graph_tests_new"), first.at("graph_tests_new"));
  EXPECT_EQ(second.at("graph_tests_retested"), 0);
}

// DAEMON_STATUS says which kind of plan costs what: the first plan selects
// a goal, the replan while driving to it follows that goal; each counts in
// its own kind and only there.
TEST(ExplorerNode, CountsPlanTimeByKind) {
  const auto [first, second] = status_after_plan_and_replan(ExplorerOptions{}, corridor(), 10, 1.5);
  ASSERT_EQ(first.at("plans"), 1);
  EXPECT_EQ(first.at("plans_select"), 1);
  EXPECT_GT(first.at("plan_cpu_us_max_select"), 0);
  for (const char* kind : {"follow", "tight", "home"}) {
    EXPECT_EQ(first.at(std::string("plans_") + kind), 0) << kind;
    EXPECT_EQ(first.at(std::string("plan_cpu_us_max_") + kind), 0) << kind;
  }
  ASSERT_EQ(second.at("plans"), 2);
  EXPECT_EQ(second.at("plans_select"), 1);
  EXPECT_EQ(second.at("plans_follow"), 1);
  EXPECT_GT(second.at("plan_cpu_us_max_follow"), 0);
  EXPECT_EQ(second.at("plan_cpu_us_max_select"), first.at("plan_cpu_us_max_select"));
}

// A keep-out the overlay cannot take out of the map fails every plan on it:
// the robot does not move, the failures are counted in DAEMON_STATUS, and no
// plan is made on the map without the keep-out. One it can take out plans.
TEST(ExplorerNode, AKeepOutThatCannotBeAppliedFailsThePlanAndIsCounted) {
  mapping::TypedPolygon area;  // given clockwise: parse_keep_out never makes one, the overlay refuses it
  area.geometry.outer() = {Point(12, 1), Point(12, 2), Point(13, 2), Point(13, 1), Point(12, 1)};
  area.edge_types = {std::vector<mapping::EdgeType>(4, mapping::EdgeType::kObstacle)};
  for (const bool clockwise : {true, false}) {
    SCOPED_TRACE(clockwise ? "clockwise" : "counter-clockwise");
    ExplorerOptions options;
    mapping::TypedPolygon given = area;
    if (!clockwise) {
      std::reverse(given.geometry.outer().begin(), given.geometry.outer().end());
    }
    options.keep_out = std::make_shared<const mapping::TypedMultiPolygon>(mapping::TypedMultiPolygon{given});
    ExplorerNode node(options);
    node.on_map(corridor(), 0);
    node.on_pose(mid_corridor(), 0);
    node.step(0);
    node.on_pose(mid_corridor(), 100'000);
    const auto cmd = node.step(100'000);
    const std::int64_t replan_us = options.mission.replan_period_us + 100'000;
    node.on_pose(mid_corridor(), replan_us);
    node.step(replan_us);
    StatusTotals status;
    node.visit_counters(status);
    if (clockwise) {
      EXPECT_EQ(cmd.v, 0.0);
      EXPECT_EQ(status.at("keep_out_failures"), 2);
      EXPECT_NE(node.last_output().status.find("keep-out"), std::string::npos) << node.last_output().status;
      EXPECT_FALSE(node.last_output().goal.has_value());
    } else {
      EXPECT_GT(cmd.v, 0.0);
      EXPECT_EQ(status.at("keep_out_failures"), 0);
      ASSERT_TRUE(node.last_output().goal.has_value());
    }
  }
}

// The laser's scans keep the mission going; a scan without ranges, or with
// more than max_beams, is refused and does not count as the laser being alive.
TEST(ExplorerNode, StopsWithoutLaserScans) {
  ExplorerOptions options;
  options.mission.scan_timeout_us = 500'000;
  ExplorerNode node(options);
  const pex::pose_t pose = mid_corridor();
  pex::laser_scan_t scan{};
  scan.nranges = 3;
  scan.ranges = {1.0f, 1.0f, 1.0f};
  pex::laser_scan_t empty{};
  pex::laser_scan_t oversized{};
  oversized.ranges.assign(options.max_beams + 1, 1.0f);
  oversized.nranges = static_cast<std::int32_t>(oversized.ranges.size());
  ASSERT_NO_THROW(node.on_map(corridor(), 0));
  for (std::int64_t t = 0; t <= 200'000; t += 100'000) {
    ASSERT_NO_THROW(node.on_pose(pose, t));
    EXPECT_THROW(node.on_scan(empty, t), std::invalid_argument);
    EXPECT_THROW(node.on_scan(oversized, t), std::invalid_argument);
    node.step(t);
  }
  EXPECT_TRUE(node.last_output().degraded);
  EXPECT_EQ(node.last_output().degraded_reason, "no laser scans");
  ASSERT_NO_THROW(node.on_scan(scan, 300'000));
  ASSERT_NO_THROW(node.on_pose(pose, 300'000));
  node.step(300'000);
  ASSERT_NO_THROW(node.on_pose(pose, 400'000));
  EXPECT_GT(node.step(400'000).v, 0.0);
  EXPECT_FALSE(node.last_output().degraded);
}

// A laser covered or dazzled (no echo on every beam) is no view: with
// min_scan_returns its scans are refused and the robot stops as without
// scans; a scan with returns again sets it going.
TEST(ExplorerNode, StopsWhenTheLaserSeesNothing) {
  ExplorerOptions options;
  options.mission.scan_timeout_us = 500'000;
  options.min_scan_returns = 5;
  ExplorerNode node(options);
  const pex::pose_t pose = mid_corridor();
  pex::laser_scan_t seeing{};
  seeing.range_max = 20.0f;
  seeing.angle_increment = 0.01f;
  seeing.ranges.assign(100, 1.2f);
  seeing.nranges = 100;
  pex::laser_scan_t blind = seeing;
  blind.ranges.assign(100, std::numeric_limits<float>::quiet_NaN());
  blind.ranges[0] = 1.2f;  // a few returns are not a view either
  ASSERT_NO_THROW(node.on_map(corridor(), 0));
  ASSERT_NO_THROW(node.on_scan(seeing, 0));
  for (std::int64_t t = 0; t <= 200'000; t += 100'000) {
    ASSERT_NO_THROW(node.on_pose(pose, t));
    node.step(t);
  }
  EXPECT_FALSE(node.last_output().degraded) << node.last_output().degraded_reason;
  for (std::int64_t t = 300'000; t <= 900'000; t += 100'000) {
    ASSERT_NO_THROW(node.on_pose(pose, t));
    EXPECT_THROW(node.on_scan(blind, t), std::invalid_argument);
    node.step(t);
  }
  EXPECT_TRUE(node.last_output().degraded);
  EXPECT_EQ(node.last_output().degraded_reason, "no laser scans");
  EXPECT_EQ(node.step(1'000'000).v, 0.0);
  ASSERT_NO_THROW(node.on_scan(seeing, 1'100'000));
  ASSERT_NO_THROW(node.on_pose(pose, 1'100'000));
  node.step(1'100'000);
  EXPECT_FALSE(node.last_output().degraded) << node.last_output().degraded_reason;
}

// Something the map does not show (or SLAM puts elsewhere) right in front of
// the robot: the scan guard holds the forward speed to what can stop before it.
// The robot held in the corridor at (10, 1.5) for 2 s of control steps with
// the same scan every step: the last command's speed and the steps the
// guard limited.
std::pair<double, std::int64_t> guarded_drive(const ExplorerOptions& options, const pex::laser_scan_t& scan) {
  ExplorerNode node(options);
  const pex::pose_t pose = mid_corridor();
  EXPECT_NO_THROW(node.on_map(corridor(), 0));
  double v = 0.0;
  for (std::int64_t t = 0; t <= 2'000'000; t += 100'000) {
    EXPECT_NO_THROW(node.on_pose(pose, t));
    EXPECT_NO_THROW(node.on_scan(scan, t));
    v = node.step(t).v;
  }
  return {v, node.counters().guard_limited_steps};
}

// A wall across the robot's way distance_m ahead (beams within 0.5 rad).
pex::laser_scan_t scan_of_wall_ahead(double distance_m) {
  pex::laser_scan_t scan{};
  scan.angle_min = -0.5f;
  scan.angle_increment = 0.01f;
  scan.range_min = 0.05f;
  scan.range_max = 20.0f;
  for (int i = 0; i <= 100; ++i) {
    const double a = scan.angle_min + i * scan.angle_increment;
    scan.ranges.push_back(static_cast<float>(distance_m / std::cos(a)));
  }
  scan.nranges = static_cast<std::int32_t>(scan.ranges.size());
  return scan;
}

TEST(ExplorerNode, TheScanGuardStopsTheRobotBeforeWhatTheLaserSeesAhead) {
  auto drive = [&](const ExplorerOptions& options, double wall_m) {
    return guarded_drive(options, scan_of_wall_ahead(wall_m));
  };
  ExplorerOptions options;
  // The guard alone: after a hold of 1 s a guard mark would turn the robot
  // away from the wall (AGuardHoldIsToldToTheMissionOnceAHold).
  options.guard_marks.lifetime_s = 0.0;
  const auto [far_v, far_limited] = drive(options, 5.0);
  EXPECT_GT(far_v, 0.3);  // 4.75 m free: full speed
  EXPECT_EQ(far_limited, 0);
  const auto [near_v, near_limited] = drive(options, 0.30);  // 5 cm between body and wall
  EXPECT_LE(near_v, std::sqrt(2.0 * options.guard.max_decel_mps2 * (0.05 - options.guard.margin_m)) + 1e-6);  // float ranges
  EXPECT_GT(near_limited, 0);
  const auto [touch_v, touch_limited] = drive(options, 0.26);
  EXPECT_EQ(touch_v, 0.0);
  options.scan_guard = false;
  EXPECT_GT(drive(options, 0.26).first, 0.0);  // the map alone would drive on
}

// A pane the map does not hold, right in front of the robot on its way:
// held still for guard_block_ms, the mission is told once a hold (and
// replans); a second hold after the way was clear is told again.
TEST(ExplorerNode, AGuardHoldIsToldToTheMissionOnceAHold) {
  auto holds = [](const ExplorerOptions& options) {
    ExplorerNode node(options);
    const pex::pose_t pose = mid_corridor();
    EXPECT_NO_THROW(node.on_map(corridor(), 0));
    bool said = false;
    // Held 3 s, free 1 s, held 2 s.
    for (std::int64_t t = 0; t <= 6'000'000; t += 100'000) {
      const bool clear = t > 3'000'000 && t <= 4'000'000;
      EXPECT_NO_THROW(node.on_pose(pose, t));
      EXPECT_NO_THROW(node.on_scan(scan_of_wall_ahead(clear ? 5.0 : 0.26), t));
      if (t % 1'000'000 == 0) {
        EXPECT_NO_THROW(node.on_map(corridor(), t));
      }
      node.step(t);
      said = said || node.last_output().status.find("held by the scan guard") != std::string::npos;
    }
    EXPECT_EQ(said, node.counters().guard_block_replans > 0);
    return std::tuple{node.counters().guard_blocks, node.counters().guard_block_replans, node.counters().guard_marks};
  };
  using Counts = std::tuple<std::int64_t, std::int64_t, std::int64_t>;
  ExplorerOptions options;
  // Marked at the first hold (the wall 1 cm ahead), the way on is a plan
  // round the mark: the robot turns away, and the wall seen again ahead
  // holds no robot that wants to drive into it.
  EXPECT_EQ(holds(options), (Counts{1, 1, 1}));
  options.guard_marks.lifetime_s = 0.0;  // no marks: the same way, held again
  EXPECT_EQ(holds(options), (Counts{2, 2, 0}));
  options.guard_block_us = 0;
  EXPECT_EQ(holds(options), (Counts{0, 0, 0}));
  options.guard_block_us = 1'000'000;
  options.mission.max_guard_blocks_per_goal = 1;  // told twice, replanned for once
  EXPECT_EQ(holds(options), (Counts{2, 1, 0}));
}

// The explorer restarted after a guard mark (kill -9, systemd starts it
// again): with the trail checkpoint it keeps the mark and plans round it,
// as the first run did; without the checkpoint, or when SLAM has started a
// new map frame meanwhile, the pane holds the robot once more.
TEST(ExplorerNode, ARestartedExplorerKeepsItsGuardMarksFromTheTrailCheckpoint) {
  enum class Restart { kFromCheckpoint, kWithoutCheckpoint, kFromCheckpointNewEpoch };
  auto holds_after_restart = [](Restart restart) {
    ExplorerOptions options;
    const pex::pose_t pose = mid_corridor();
    auto slam_update = [](std::int64_t epoch, std::int64_t generation) {
      pex::slam_update_t u{};
      u.epoch = epoch;
      u.generation = generation;
      pex::particle_t p{};
      p.x = 10.0;
      p.y = 1.5;
      p.parent = 0;
      u.particles.push_back(p);
      u.nparticles = 1;
      return u;
    };
    auto run = [&](ExplorerNode& node, std::int64_t from, std::int64_t to) {
      for (std::int64_t t = from; t <= to; t += 100'000) {
        EXPECT_NO_THROW(node.on_pose(pose, t));
        EXPECT_NO_THROW(node.on_scan(scan_of_wall_ahead(0.26), t));
        if (t % 1'000'000 == 0) {
          EXPECT_NO_THROW(node.on_map(corridor(), t));
        }
        node.step(t);
      }
    };
    ExplorerNode first(options);
    EXPECT_NO_THROW(first.on_slam_update(slam_update(1, 0)));
    run(first, 0, 2'000'000);
    EXPECT_EQ(first.counters().guard_marks, 1);
    ExplorerNode second(options);
    if (restart != Restart::kWithoutCheckpoint) {
      EXPECT_EQ(second.restore_trails(first.trail_checkpoint()), "");
    }
    const std::int64_t epoch = restart == Restart::kFromCheckpointNewEpoch ? 2 : 1;
    EXPECT_NO_THROW(second.on_slam_update(slam_update(epoch, epoch == 1 ? 1 : 0)));
    run(second, 2'100'000, 5'000'000);
    return second.counters().guard_blocks;
  };
  EXPECT_EQ(holds_after_restart(Restart::kFromCheckpoint), 0);
  EXPECT_EQ(holds_after_restart(Restart::kWithoutCheckpoint), 1);
  EXPECT_EQ(holds_after_restart(Restart::kFromCheckpointNewEpoch), 1);

  // The file of an explorer from before the marks (the trails alone) is taken up.
  TrailKeeper old_file;
  pex::slam_update_t u{};
  u.epoch = 1;
  pex::particle_t p{};
  p.parent = 0;
  u.particles.push_back(p);
  u.nparticles = 1;
  EXPECT_NO_THROW(old_file.on_slam_update(u));
  ExplorerNode node{ExplorerOptions{}};
  EXPECT_EQ(node.restore_trails(old_file.checkpoint()), "");
  EXPECT_NE(node.restore_trails("PEXTRMRK and then nothing of the sort"), "");
}

// The laser blind to both sides (beams beyond 0.5 rad without a return):
// the guard reads the corridor's walls from the map for them, and walls
// beside the robot do not slow it.
TEST(ExplorerNode, TheGuardReadsTheMapsWallsWhereTheLaserIsBlind) {
  pex::laser_scan_t scan{};
  scan.angle_min = static_cast<float>(-M_PI / 2);
  scan.angle_increment = static_cast<float>(M_PI / 180);
  scan.range_min = 0.05f;
  scan.range_max = 20.0f;
  for (int i = 0; i <= 180; ++i) {
    const double a = scan.angle_min + i * scan.angle_increment;
    scan.ranges.push_back(std::abs(a) < 0.5 ? static_cast<float>(5.0 / std::cos(a)) : 0.0f);
  }
  scan.nranges = static_cast<std::int32_t>(scan.ranges.size());
  ExplorerOptions options;
  const auto [v, limited] = guarded_drive(options, scan);
  EXPECT_GT(v, 0.3);
  EXPECT_EQ(limited, 0);
  // The corridor's walls 1.5 m to either side are within 2 m from 48.6
  // degrees on: 42 beams a side, in each of the 21 scans.
  ExplorerNode node(options);
  const pex::pose_t pose = mid_corridor();
  ASSERT_NO_THROW(node.on_map(corridor(), 0));
  ASSERT_NO_THROW(node.on_pose(pose, 0));
  ASSERT_NO_THROW(node.on_scan(scan, 0));
  EXPECT_EQ(node.counters().guard_map_wall_beams, 84);
  options.guard_scan.map_walls_m = 0.0;
  ExplorerNode off(options);
  ASSERT_NO_THROW(off.on_map(corridor(), 0));
  ASSERT_NO_THROW(off.on_pose(pose, 0));
  ASSERT_NO_THROW(off.on_scan(scan, 0));
  EXPECT_EQ(off.counters().guard_map_wall_beams, 0);
}

// A wall's end just inside the band the body sweeps, its last return just
// outside it (the next beam passes the end): the returns alone let the robot
// on at full speed, the guard's points past the wall's end hold it back
// (planning::guard_points; "Scan guard" in docs/exploration.md).
TEST(ExplorerNode, TheScanGuardKeepsClearOfAWallsEndItsLastReturnFallsShortOf) {
  // A wall across the way 0.2 m ahead, from y = -1 to its end at y = -0.248
  // (the body: |y| < 0.25), beams 0.01 rad apart with one at y = -0.2510;
  // the next, at y = -0.2459, passes the end and meets a wall 5 m away.
  constexpr double kWallX = 0.2, kEndY = -0.248;
  pex::laser_scan_t scan{};
  scan.angle_increment = 0.01f;
  scan.angle_min = static_cast<float>(std::atan2(-0.2510, kWallX) - 40 * 0.01);
  scan.range_min = 0.05f;
  scan.range_max = 20.0f;
  int on_wall = 0;
  for (int i = 0; i <= 100; ++i) {
    const double a = static_cast<double>(scan.angle_min) + i * static_cast<double>(scan.angle_increment);
    const double y_at_wall = kWallX * std::tan(a);
    const bool hits = std::cos(a) > 0.0 && y_at_wall >= -1.0 && y_at_wall <= kEndY;
    on_wall += hits;
    scan.ranges.push_back(static_cast<float>(hits ? kWallX / std::cos(a) : 5.0));
  }
  scan.nranges = static_cast<std::int32_t>(scan.ranges.size());
  ASSERT_GT(on_wall, 20);
  ExplorerOptions options;
  options.guard.side_margin_m = 0.0;  // the crawl beside a return would hold both alike
  options.guard_scan.wall_end_reach_m = 0.0;
  const auto [returns_v, returns_limited] = guarded_drive(options, scan);
  EXPECT_GT(returns_v, 0.3);  // every return outside the band: full speed
  EXPECT_EQ(returns_limited, 0);
  options.guard_scan = {};
  const auto [ends_v, ends_limited] = guarded_drive(options, scan);
  EXPECT_LT(ends_v, 0.2);  // braking room to the wall's end: at most 0.2 - 0.03 - 0.045 m
  EXPECT_GT(ends_limited, 0);
}

// A band left across a door (a scan at a bad pose, a person in the doorway)
// cuts the planning map in two; the laser sees through the door now. With the
// live view the explorer plans through it, without it the far room's frontier
// has no path.
// Room A [0,4] x [0,4], room B [4.2,8.2] x [0,4] with a frontier on its far
// side; the map has lost the 1 m door between them (y = 1.5 .. 2.5) to a band.
pex::polygon_map_t two_rooms_door_closed() {
  return map_of({ring(0, false, {{0, 0}, {4, 0}, {4, 4}, {0, 4}}),
                 ring(1, false, {{4.2, 0}, {8.2, 0}, {8.2, 4}, {4.2, 4}}, {0, 1, 0, 0})});
}

// The laser's scan in the world where that door is open.
pex::laser_scan_t two_rooms_scan(const pex::pose_t& pose) {
  std::vector<mapping::testing::Wall> walls;
  mapping::testing::add_box(walls, 0, 0, 8.2, 4);
  for (const double x : {4.0, 4.2}) {
    walls.push_back({Point(x, 0.0), Point(x, 1.5)});
    walls.push_back({Point(x, 2.5), Point(x, 4.0)});
  }
  const mapping::testing::ScanSpec spec;
  pex::laser_scan_t scan{};
  scan.angle_min = static_cast<float>(spec.angle_min);
  scan.angle_increment = static_cast<float>(spec.angle_increment);
  scan.range_min = 0.05f;
  scan.range_max = static_cast<float>(spec.range_max_m);
  scan.ranges = mapping::testing::cast_scan(walls, geometry::Pose2{pose.x, pose.y, pose.theta}, spec);
  scan.nranges = static_cast<std::int32_t>(scan.ranges.size());
  return scan;
}

TEST(ExplorerNode, TheLiveViewOpensADoorTheMapHasClosed) {
  const auto map = two_rooms_door_closed();
  pex::pose_t pose{};
  pose.x = 2.5;
  pose.y = 2.0;  // facing the door
  const auto scan = two_rooms_scan(pose);
  auto goal_after_a_while = [&](double live_range_m) {
    ExplorerOptions options;
    options.live_view.range_m = live_range_m;
    options.mission.planner.approach_range_m = 0.0;  // the door itself, not a look from afar
    options.mission.look_around = false;
    ExplorerNode node(options);
    std::optional<Point> goal;
    for (std::int64_t t = 0; t <= 3'000'000 && !goal; t += 100'000) {
      EXPECT_NO_THROW(node.on_map(map, t));
      EXPECT_NO_THROW(node.on_pose(pose, t));
      EXPECT_NO_THROW(node.on_scan(scan, t));
      node.step(t);
      goal = node.last_output().goal;
    }
    return goal;
  };
  const auto with = goal_after_a_while(3.0);
  ASSERT_TRUE(with.has_value());
  EXPECT_GT(with->x(), 4.2);  // in room B, through the door
  EXPECT_FALSE(goal_after_a_while(0.0).has_value());
}

// The same, with the door behind the robot, in the laser's blind 90 degrees:
// before it calls room B unreachable it turns on the spot, sees the door, and
// goes.
TEST(ExplorerNode, ItLooksAroundBeforeItCallsAFrontierUnreachable) {
  ExplorerOptions options;
  options.live_view.range_m = 3.0;
  options.mission.planner.approach_range_m = 0.0;
  ExplorerNode node(options);
  pex::pose_t pose{};
  pose.x = 2.5;
  pose.y = 2.0;
  pose.theta = 3.14159;  // facing room A's far wall
  std::optional<Point> goal;
  for (std::int64_t t = 0; t <= 30'000'000 && !goal; t += 100'000) {
    pose.utime = t;
    if (t % 1'000'000 == 0) {
      EXPECT_NO_THROW(node.on_map(two_rooms_door_closed(), t));
    }
    EXPECT_NO_THROW(node.on_pose(pose, t));
    EXPECT_NO_THROW(node.on_scan(two_rooms_scan(pose), t));
    const auto cmd = node.step(t);
    EXPECT_EQ(cmd.v, 0.0) << "it stands until it has a goal";
    pose.theta += cmd.omega * 0.1;
    goal = node.last_output().goal;
    ASSERT_FALSE(planning::is_finished(node.last_output().phase)) << node.last_output().status;
  }
  ASSERT_TRUE(goal.has_value());
  EXPECT_GT(goal->x(), 4.2);
  EXPECT_EQ(node.last_output().looks_around, 1);
}

pex::slam_update_t slam_update(std::int64_t generation, std::vector<std::pair<double, int>> x_and_parent,
                               std::int32_t best = 0) {
  pex::slam_update_t u{};
  u.epoch = 1;
  u.generation = generation;
  u.best = best;
  for (const auto& [x, parent] : x_and_parent) {
    pex::particle_t p{};
    p.x = x;
    p.y = parent;  // tells the lineages apart
    p.parent = parent;
    u.particles.push_back(p);
  }
  u.nparticles = static_cast<std::int32_t>(u.particles.size());
  return u;
}

// The trail the keeper gives a tight plan on a map made by `particle` at
// `generation` (particle -1: a map not made from SLAM particles).
std::shared_ptr<const std::vector<Point>> trail_for_map_of(TrailKeeper& keeper, int particle,
                                                           std::int64_t generation = 0) {
  auto map = map_of({});
  map.particle = particle;
  map.generation = generation;
  keeper.on_map(map);
  return keeper.trail_for_map();
}

// The trail a tight plan goes along is the one of the map's particle at the
// map's generation: the particle whose poses built that map.
TEST(TrailKeeper, GivesTheTrailOfTheMapsParticleAndGeneration) {
  TrailKeeper keeper;
  keeper.on_slam_update(slam_update(0, {{0.0, 0}, {0.0, 1}}));
  keeper.on_slam_update(slam_update(1, {{1.0, 0}, {1.0, 1}}));
  keeper.on_slam_update(slam_update(2, {{2.0, 1}, {2.0, 1}}, 1));
  auto trail = trail_for_map_of(keeper, 0, 1);  // the mapper is one update behind
  ASSERT_NE(trail, nullptr);
  ASSERT_EQ(trail->size(), 2u);
  EXPECT_DOUBLE_EQ(trail->back().x(), 1.0);
  EXPECT_DOUBLE_EQ(trail->back().y(), 0.0) << "particle 0's own lineage";
  trail = trail_for_map_of(keeper, 0, 2);
  ASSERT_NE(trail, nullptr);
  EXPECT_DOUBLE_EQ(trail->front().y(), 1.0) << "at generation 2, particle 0 descends from particle 1";
  EXPECT_EQ(trail_for_map_of(keeper, 0, 9), nullptr) << "no update of that generation seen";

  // A map not made from particles: the trail of the poses the explorer got.
  keeper.on_pose({5, 5, 0});
  keeper.on_pose({6, 5, 0});
  trail = trail_for_map_of(keeper, -1);
  ASSERT_NE(trail, nullptr);
  EXPECT_EQ(trail->size(), 2u);
  EXPECT_DOUBLE_EQ(trail->back().x(), 6.0);
}

// The robot came from room A through the door into room B; the map now has
// the door shut (a band across it), and room A's west side is still a
// frontier. With the margin there is no path back; the tight fallback goes
// along the way the robot drove, from the SLAM_UPDATEs of the map's particle.
TEST(ExplorerNode, ItGoesBackThroughAGapTheMapShutAlongTheWayItCame) {
  auto map = map_of({ring(0, false, {{0, 0}, {4, 0}, {4, 4}, {0, 4}}, {0, 0, 0, 1}),
                     ring(1, false, {{4.2, 0}, {8.2, 0}, {8.2, 4}, {4.2, 4}})});
  // `restart`: the explorer is restarted in room B, before any plan,
  // from the trail checkpoint its first run wrote (or from none).
  enum class Restart { kNo, kFromCheckpoint, kWithoutCheckpoint };
  auto goal_after_a_while = [&](double trail_corridor_m, Restart restart = Restart::kNo) {
    ExplorerOptions options;
    options.mission.planner.approach_range_m = 0.0;
    options.mission.planner.trail_corridor_m = trail_corridor_m;
    options.mission.look_around = false;
    options.mission.back_out_m = 0.0;  // the trail alone, not the mission's own way back
    auto first = std::make_unique<ExplorerNode>(options);
    ExplorerNode* node_ptr = first.get();
    std::int64_t generation = 0;
    for (double x = 2.0; x <= 6.0; x += 0.2) {  // the drive from room A into room B
      pex::slam_update_t u{};
      u.epoch = 1;
      u.generation = generation++;
      pex::particle_t p{};
      p.x = x;
      p.y = 2.0;
      p.parent = 0;
      u.particles.push_back(p);
      u.nparticles = 1;
      EXPECT_NO_THROW(node_ptr->on_slam_update(u));
    }
    std::unique_ptr<ExplorerNode> restarted;
    if (restart != Restart::kNo) {
      restarted = std::make_unique<ExplorerNode>(options);
      if (restart == Restart::kFromCheckpoint) {
        EXPECT_EQ(restarted->restore_trails(first->trail_checkpoint()), "");
      }
      first.reset();
      node_ptr = restarted.get();
    }
    ExplorerNode& node = *node_ptr;
    map.particle = 0;
    map.generation = generation - 1;
    pex::pose_t pose{};
    pose.x = 6.0;
    pose.y = 2.0;
    std::optional<Point> goal;
    for (std::int64_t t = 0; t <= 10'000'000 && !goal; t += 100'000) {
      if (t % 1'000'000 == 0) {
        EXPECT_NO_THROW(node.on_map(map, t));
      }
      pose.utime = t;
      EXPECT_NO_THROW(node.on_pose(pose, t));
      node.step(t);
      goal = node.last_output().goal;
      if (planning::is_finished(node.last_output().phase)) break;
    }
    EXPECT_EQ(node.counters().tight_plans_without_trail == 0, restart != Restart::kWithoutCheckpoint);
    return std::make_pair(goal, node.last_output().phase);
  };
  const auto [with, with_phase] = goal_after_a_while(0.05);
  ASSERT_TRUE(with.has_value());
  EXPECT_LT(with->x(), 1.0) << "room A's frontier, back through the door";
  const auto [without, phase] = goal_after_a_while(0.0);
  EXPECT_FALSE(without.has_value());
  EXPECT_EQ(phase, planning::Phase::kDoneWithUnreachable);

  // The way it came survives a restart of the explorer with its checkpoint,
  // and only with it.
  const auto [restored, restored_phase] = goal_after_a_while(0.05, Restart::kFromCheckpoint);
  ASSERT_TRUE(restored.has_value()) << planning::to_string(restored_phase);
  EXPECT_LT(restored->x(), 1.0);
  const auto [forgotten, forgotten_phase] = goal_after_a_while(0.05, Restart::kWithoutCheckpoint);
  EXPECT_FALSE(forgotten.has_value());
  EXPECT_EQ(forgotten_phase, planning::Phase::kDoneWithUnreachable);
}

TEST(TrailKeeper, BothTrailsSurviveARestartAndABadCheckpointChangesNothing) {
  TrailKeeper before;
  before.on_slam_update(slam_update(0, {{0.0, 0}, {0.0, 1}}));
  before.on_slam_update(slam_update(1, {{1.0, 1}, {1.0, 1}}, 1));
  before.on_pose({5, 5, 0});
  before.on_pose({6, 5, 0});
  const std::string bytes = before.checkpoint();

  TrailKeeper after;
  ASSERT_EQ(after.restore(bytes), "");
  auto trail = trail_for_map_of(after, 0, 1);  // any particle of the restored generation has the best trail
  ASSERT_NE(trail, nullptr);
  ASSERT_EQ(trail->size(), 2u);
  EXPECT_DOUBLE_EQ(trail->front().y(), 1.0) << "particle 1's lineage, the best";
  // SLAM goes on: a resync on the restored trail.
  const auto r = after.on_slam_update(slam_update(2, {{2.0, 0}, {2.0, 1}}));
  EXPECT_TRUE(r.resynced);
  trail = trail_for_map_of(after, 0, 2);
  ASSERT_NE(trail, nullptr);
  EXPECT_EQ(trail->size(), 3u);
  // The poses' trail goes on from where it was.
  after.on_pose({7, 5, 0});
  trail = trail_for_map_of(after, -1);
  ASSERT_NE(trail, nullptr);
  EXPECT_EQ(trail->size(), 3u);
  EXPECT_DOUBLE_EQ(trail->front().x(), 5.0);

  // Cut short, or another kind of file: refused, the trails held kept.
  for (const std::string& bad : {bytes.substr(0, bytes.size() / 2), std::string("polyexplore-mission 1\nend\n")}) {
    EXPECT_NE(after.restore(bad), "");
    trail = after.trail_for_map();
    ASSERT_NE(trail, nullptr);
    EXPECT_EQ(trail->size(), 3u);
  }
  // A fresh keeper's checkpoint (nothing held) restores to nothing held.
  TrailKeeper empty;
  ASSERT_EQ(empty.restore(TrailKeeper().checkpoint()), "");
  EXPECT_EQ(empty.trail_for_map(), nullptr);
}

TEST(TrailKeeper, RefusesABadSlamUpdateAndKeepsItsTrails) {
  TrailKeeper keeper;
  keeper.on_slam_update(slam_update(0, {{0.0, 0}}));
  auto bad = slam_update(1, {{1.0, 3}});  // parent out of range
  EXPECT_THROW(keeper.on_slam_update(bad), std::invalid_argument);
  auto lying = slam_update(1, {{1.0, 0}});
  lying.nparticles = 5;
  EXPECT_THROW(keeper.on_slam_update(lying), std::invalid_argument);
  auto nan = slam_update(1, {{NAN, 0}});
  EXPECT_THROW(keeper.on_slam_update(nan), std::invalid_argument);
  keeper.on_slam_update(slam_update(1, {{1.0, 0}}));
  const auto trail = trail_for_map_of(keeper, 0, 1);
  ASSERT_NE(trail, nullptr);
  EXPECT_EQ(trail->size(), 2u);
}

}  // namespace
}  // namespace pex::explorer
