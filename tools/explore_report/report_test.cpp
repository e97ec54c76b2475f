#include "report.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "map_message.hpp"
#include "runtime/channels.hpp"

namespace pex::explore_report {
namespace {

namespace bg = boost::geometry;
namespace ch = runtime::channels;

// A 6 x 4 m room; the robot starts in its middle.
sim::World room() {
  auto parsed = sim::parse_world("START 3 2 0\nLINESTRING(0 0, 6 0, 6 4, 0 4, 0 0)\n", "room");
  return std::get<sim::World>(parsed);
}

class TempLog {
 public:
  TempLog()
      : path_(std::filesystem::temp_directory_path() /
              ("pex_explore_report_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++) + ".lcm")) {}
  ~TempLog() { std::filesystem::remove(path_); }
  std::string path() const { return path_.string(); }

  template <class Msg>
  void add(std::string_view channel, const Msg& msg) {
    std::vector<std::uint8_t> buffer(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
    add_raw(channel, buffer);
  }
  void add_raw(std::string_view channel, std::vector<std::uint8_t> data) {
    events_.push_back({std::string(channel), std::move(data)});
  }
  void write() const {
    lcm::LogFile log(path(), "w");
    ASSERT_TRUE(log.good());
    std::int64_t t = 1'000'000;
    for (const auto& [channel, data] : events_) {
      lcm::LogEvent event{};
      event.timestamp = t += 1000;
      event.channel = channel;
      event.datalen = static_cast<std::int32_t>(data.size());
      event.data = const_cast<std::uint8_t*>(data.data());
      ASSERT_EQ(log.writeEvent(&event), 0);
    }
  }

 private:
  static inline int counter_ = 0;
  std::filesystem::path path_;
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> events_;
};

pex::daemon_status_t status(const std::string& name, const std::vector<std::pair<std::string, std::int64_t>>& counters) {
  pex::daemon_status_t s{};
  s.name = name;
  s.state = pex::daemon_status_t::STATE_OK;
  for (const auto& [k, v] : counters) {
    s.counter_names.push_back(k);
    s.counter_values.push_back(v);
  }
  s.ncounters = static_cast<std::int32_t>(counters.size());
  return s;
}

TEST(ExploreReport, FullLogGivesEveryField) {
  const auto world = room();
  const auto reachable = evaluation::reachable_free_space(world, 0.25, world.start);

  // The map: the room's left half, all obstacle edges, in the start frame
  // (origin at (3, 2) world, same heading).
  mapping::Polygon left;
  bg::read_wkt("POLYGON((-3 -2, 0 -2, 0 2, -3 2, -3 -2))", left);
  bg::correct(left);
  const auto map = explorer::encode_map(mapping::with_uniform_type({left}, mapping::EdgeType::kObstacle), 5);

  pex::explore_state_t state{};
  state.phase = pex::explore_state_t::PHASE_DONE_WITH_UNREACHABLE;
  state.strategy = "greedy";
  state.distance_travelled_m = 12.5;
  state.mission_time_s = 80.0;
  state.goals_reached = 4;
  state.plans = 7;
  pex::sim_clock_t clock{};
  clock.sim_time_us = 95'500'000;
  clock.collisions = 1;

  TempLog log;
  log.add(ch::kMap, map);
  log.add_raw(ch::kMap, {1, 2, 3});  // garbage: counted, skipped
  log.add(ch::kExploreState, state);
  log.add(ch::kSimClock, clock);
  log.add(ch::kDaemonStatus,
          status("explorer", {{"plan_us_p50", 1500},
                              {"plan_us_p99", 12000},
                              {"plan_cpu_us_p99", 9000},
                              {"plans_select", 5},
                              {"plan_cpu_us_p99_select", 9000},
                              {"plans_tight", 2},
                              {"plan_cpu_us_p99_tight", 4000},
                              {"goals_seen", 9},
                              {"goals_blocked", 1},
                              {"goals_no_progress", 2},
                              {"goals_overdue", 3},
                              {"goals_came_back", 1}}));
  log.add(ch::kDaemonStatus, status("slam", {{"plan_us_p50", 99}}));  // not the explorer's
  log.write();

  std::string error;
  const auto contents = read_log(log.path(), &error);
  ASSERT_TRUE(contents) << error;
  EXPECT_EQ(contents->events, 6);
  EXPECT_EQ(contents->rejected, 1);

  ReportOptions options;
  options.map_in_world = world.start;
  mapping::TypedMultiPolygon map_world;
  const auto r = make_report("room", *contents, world, reachable, options, &map_world);
  EXPECT_EQ(r.strategy, "greedy");
  EXPECT_EQ(r.phase, "done_with_unreachable");
  EXPECT_DOUBLE_EQ(*r.sim_time_s, 95.5);
  EXPECT_DOUBLE_EQ(*r.path_m, 12.5);
  EXPECT_NEAR(*r.explored_m2, 12.0, 1e-9);
  EXPECT_NEAR(*r.reachable_m2, bg::area(reachable), 1e-12);
  EXPECT_NEAR(*r.coverage, 0.5, 1e-9);  // the room and its reachable space are symmetric
  // The map holds the reachable space's left half and the two corners the
  // robot cannot reach: IoU = A/2 / (A + 12 - A/2).
  const double a = bg::area(reachable);
  EXPECT_NEAR(*r.iou, 0.5 * a / (0.5 * a + 12.0), 1e-9);
  // 10 m of the map's 14 m of obstacle edges on walls, and the 0.1 m ends of
  // the x = 3 edge near the walls it meets.
  EXPECT_NEAR(*r.obstacle_on_wall, 10.2 / 14.0, 1e-9);
  EXPECT_EQ(r.collisions, 1);
  EXPECT_EQ(r.goals, 4);
  EXPECT_EQ(r.plans, 7);
  EXPECT_DOUBLE_EQ(*r.plan_ms_p50, 1.5);
  EXPECT_DOUBLE_EQ(*r.plan_ms_p99, 12.0);
  EXPECT_FALSE(r.control_ms_p99);  // the counter is absent
  EXPECT_EQ(r.goals_seen, 9);
  EXPECT_EQ(r.goals_given_up, 7);  // blocked, no progress, overdue and came back
  // Plans by kind: the kinds the explorer counted, in planning::PlanKind's order.
  ASSERT_EQ(r.plans_by_kind.size(), 2u);
  EXPECT_EQ(r.plans_by_kind[0].kind, "select");
  EXPECT_EQ(r.plans_by_kind[0].plans, 5);
  EXPECT_DOUBLE_EQ(*r.plans_by_kind[0].cpu_ms_p99, 9.0);
  EXPECT_EQ(r.plans_by_kind[1].kind, "tight");
  EXPECT_EQ(r.plans_by_kind[1].plans, 2);
  EXPECT_DOUBLE_EQ(*r.plans_by_kind[1].cpu_ms_p99, 4.0);

  const std::string json = to_json(r);
  EXPECT_EQ(json.rfind("{\"world\":\"room\",\"strategy\":\"greedy\",\"phase\":\"done_with_unreachable\","
                       "\"sim_time_s\":95.500,\"path_m\":12.500,\"explored_m2\":12.000,",
                       0),
            0u)
      << json;
  EXPECT_NE(json.find("\"coverage\":0.50000,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"collisions\":1,\"goals\":4,\"plans\":7,\"plan_ms_p50\":1.500,\"plan_ms_p99\":12.000,"
                      "\"control_ms_p99\":null,\"plan_cpu_ms_p50\":null,\"plan_cpu_ms_p99\":9.000,"
                      "\"plans_select\":5,\"plan_cpu_ms_p99_select\":9.000,\"plans_tight\":2,"
                      "\"plan_cpu_ms_p99_tight\":4.000,"
                      "\"map_outside_free_m2\":null,\"map_unreachable_free_m2\":null,\"slam_error_mean_m\":null,"
                      "\"slam_error_max_m\":null,\"slam_heading_error_mean_deg\":null,\"slam_error_aligned_mean_m\":null,\"scored_map\":\"MAP\","
                      "\"goals_seen\":9,\"goals_given_up\":7}"),
            std::string::npos)
      << json;

  // The map, moved to the world, lies on the room's left half.
  ASSERT_EQ(map_world.size(), 1u);
  for (const auto& p : map_world.front().geometry.outer()) {
    EXPECT_TRUE(std::abs(p.x()) < 1e-12 || std::abs(p.x() - 3.0) < 1e-12) << p.x();
    EXPECT_TRUE(std::abs(p.y()) < 1e-12 || std::abs(p.y() - 4.0) < 1e-12) << p.y();
  }
  const std::string svg = to_svg(world, reachable, map_world, world.start, 0.25, 0.1);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("#e03030"), std::string::npos);  // the missed right half
  const auto off_wall = svg.find("stroke=\"#ff00ff\"");  // the x = 3 edge, off the walls
  ASSERT_NE(off_wall, std::string::npos);
  EXPECT_LT(svg.find("d=\"M", off_wall), svg.find("/>", off_wall));
}

// MAP_FREE (the explored free space) is scored when the log has it; MAP
// (free space minus the obstacle band) when asked for, or when MAP_FREE is absent.
TEST(ExploreReport, ScoresTheExploredFreeSpaceWhenTheLogHasIt) {
  const auto world = room();
  const auto reachable = evaluation::reachable_free_space(world, 0.25, world.start);
  auto half = [](const char* wkt) {
    mapping::Polygon p;
    bg::read_wkt(wkt, p);
    bg::correct(p);
    return explorer::encode_map(mapping::with_uniform_type({p}, mapping::EdgeType::kObstacle), 5);
  };
  TempLog log;
  log.add(ch::kMapFree, half("POLYGON((-3 -2, 0 -2, 0 2, -3 2, -3 -2))"));  // the left half (start frame)
  log.add(ch::kMap, half("POLYGON((-3 -2, -1.5 -2, -1.5 2, -3 2, -3 -2))"));  // a quarter
  log.write();
  const auto contents = read_log(log.path(), nullptr);
  ASSERT_TRUE(contents && contents->map && contents->free_space);
  ReportOptions options;
  options.map_in_world = world.start;
  const auto scored_free = make_report("room", *contents, world, reachable, options);
  EXPECT_EQ(scored_free.scored_map, "MAP_FREE");
  EXPECT_NEAR(*scored_free.explored_m2, 12.0, 1e-9);
  EXPECT_NEAR(*scored_free.coverage, 0.5, 1e-9);
  options.scored_map = ScoredMap::kPlanningMap;
  const auto scored_planning = make_report("room", *contents, world, reachable, options);
  EXPECT_EQ(scored_planning.scored_map, "MAP");
  EXPECT_NEAR(*scored_planning.explored_m2, 6.0, 1e-9);
  EXPECT_LT(*scored_planning.coverage, 0.3);
  // Without MAP_FREE in the log, auto scores MAP; asking for MAP_FREE scores nothing.
  auto without_free = *contents;
  without_free.free_space.reset();
  options.scored_map = ScoredMap::kAuto;
  EXPECT_EQ(make_report("room", without_free, world, reachable, options).scored_map, "MAP");
  options.scored_map = ScoredMap::kFreeSpace;
  const auto none = make_report("room", without_free, world, reachable, options);
  EXPECT_FALSE(none.scored_map);
  EXPECT_FALSE(none.coverage);
}

TEST(ExploreReport, MissingChannelsGiveNulls) {
  const auto world = room();
  const auto reachable = evaluation::reachable_free_space(world, 0.25, world.start);
  pex::explore_state_t state{};
  state.phase = pex::explore_state_t::PHASE_MOVING;
  state.mission_time_s = 12.25;
  TempLog log;
  log.add(ch::kExploreState, state);
  log.add(ch::kDaemonStatus, status("explorer", {}));
  log.write();
  const auto contents = read_log(log.path(), nullptr);
  ASSERT_TRUE(contents);
  const auto r = make_report("room", *contents, world, reachable, {});
  char reachable_m2[32];
  std::snprintf(reachable_m2, sizeof reachable_m2, "%.3f", bg::area(reachable));
  EXPECT_EQ(to_json(r), std::string("{\"world\":\"room\",\"strategy\":null,\"phase\":\"moving\",\"sim_time_s\":12.250,"
                                    "\"path_m\":0.000,\"explored_m2\":null,\"reachable_m2\":") +
                            reachable_m2 +
                            ",\"coverage\":null,\"iou\":null,\"obstacle_on_wall\":null,\"collisions\":null,"
                            "\"goals\":0,\"plans\":0,\"plan_ms_p50\":null,\"plan_ms_p99\":null,\"control_ms_p99\":null,"
                            "\"plan_cpu_ms_p50\":null,\"plan_cpu_ms_p99\":null,\"map_outside_free_m2\":null,"
                            "\"map_unreachable_free_m2\":null,\"slam_error_mean_m\":null,\"slam_error_max_m\":null,"
                            "\"slam_heading_error_mean_deg\":null,\"slam_error_aligned_mean_m\":null,\"scored_map\":null,"
                            "\"goals_seen\":null,\"goals_given_up\":null}");
}

// The map's free space that is not reachable, split: beyond the room's wall
// (wrong) and in the room's corners, where a disk cannot sweep (right).
TEST(ExploreReport, UnreachableMapSpaceIsSplitIntoBeyondTheWallsAndCornersTheDiskMisses) {
  const auto world = room();
  const auto reachable = evaluation::reachable_free_space(world, 0.25, world.start);
  const auto world_free = evaluation::configuration_free_component(world, 0.001, world.start);
  // The room's left half, reaching 0.5 m past its west wall (start frame).
  mapping::Polygon left;
  bg::read_wkt("POLYGON((-3.5 -2, 0 -2, 0 2, -3.5 2, -3.5 -2))", left);
  bg::correct(left);
  TempLog log;
  log.add(ch::kMap, explorer::encode_map(mapping::with_uniform_type({left}, mapping::EdgeType::kObstacle), 5));
  log.write();
  std::string error;
  const auto contents = read_log(log.path(), &error);
  ASSERT_TRUE(contents) << error;
  ReportOptions options;
  options.map_in_world = world.start;
  const auto r = make_report("room", *contents, world, reachable, options, nullptr, &world_free);
  ASSERT_TRUE(r.map_outside_free_m2 && r.map_unreachable_free_m2);
  // The strip beyond the wall, and the 1 mm inside the walls the map
  // covers that the 1 mm disk's free space leaves out: along the west wall
  // (4 m) and along the north and south walls (3 m each).
  EXPECT_NEAR(*r.map_outside_free_m2, 0.5 * 4.0 + 0.001 * (4.0 + 2 * 3.0), 1e-4);
  // Two corners the 0.25 m disk cannot reach: r^2 (1 - pi / 4) each.
  EXPECT_NEAR(*r.map_unreachable_free_m2, 2.0 * 0.0625 * (1.0 - std::numbers::pi / 4.0), 0.01);
  EXPECT_NE(to_json(r).find("\"map_outside_free_m2\":2.0"), std::string::npos) << to_json(r);
  // Without the world's free region the split is not made.
  EXPECT_FALSE(make_report("room", *contents, world, reachable, options).map_outside_free_m2);
}

// SLAM's published pose against the simulator's truth at the same time,
// the MAP frame placed at the start pose.
TEST(ExploreReport, PoseAuditComparesSlamPosesWithTheTruthAtTheSameTime) {
  const auto world = room();  // START 3 2 0
  LogContents log;
  log.events = 1;
  log.slam_poses = {{1'000'000, {0.0, 0.0, 0.0}}, {2'000'000, {1.0, 0.0, 0.0}}, {5'000'000, {2.0, 0.0, 0.0}}};
  log.truth = {{2'000'000, {4.0, 2.0, 0.1}}, {1'005'000, {3.0, 2.1, 0.0}},  // not in time order
               {5'100'000, {9.0, 9.0, 0.0}}};                            // 100 ms off: no pair
  ReportOptions options;
  options.map_in_world = world.start;
  const auto r = make_report("room", log, world, evaluation::reachable_free_space(world, 0.25, world.start), options);
  ASSERT_TRUE(r.slam_error_mean_m && r.slam_error_max_m && r.slam_heading_error_mean_deg);
  EXPECT_NEAR(*r.slam_error_mean_m, 0.05, 1e-9);
  EXPECT_NEAR(*r.slam_error_max_m, 0.1, 1e-9);
  EXPECT_NEAR(*r.slam_heading_error_mean_deg, 0.05 * 180.0 / std::numbers::pi, 1e-9);
  // The pairs behind the figures (--pose-errors-out), in the log's order.
  const auto pairs = pose_errors(log, options.map_in_world);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].utime, 1'000'000);
  EXPECT_NEAR(pairs[0].slam_in_world.x_m, 3.0, 1e-12);
  EXPECT_NEAR(pairs[0].truth.y_m, 2.1, 1e-12);
  EXPECT_NEAR(pairs[0].error_m, 0.1, 1e-9);
  EXPECT_NEAR(pairs[1].error_m, 0.0, 1e-9);
  EXPECT_NEAR(pairs[1].heading_error_rad, -0.1, 1e-12);  // SLAM's heading minus the truth's
  // The same poses with the map frame at the world's origin are 2-3 m off,
  // but a rigid motion of the trajectory as a whole brings them close again.
  options.map_in_world = {};
  const auto off = make_report("room", log, world, evaluation::reachable_free_space(world, 0.25, world.start), options);
  EXPECT_GT(*off.slam_error_mean_m, 2.0);
  ASSERT_TRUE(off.slam_error_aligned_mean_m);
  EXPECT_LT(*off.slam_error_aligned_mean_m, 0.1);
}

TEST(ExploreReport, AlignedPoseErrorSeesABentTrajectoryButNotATurnedOne) {
  const auto world = room();
  ReportOptions options;
  options.map_in_world = world.start;
  LogContents turned, bent;
  turned.events = bent.events = 1;
  // The truth drives 10 m along x and back, to (0.5, 0).
  for (int i = 0; i <= 20; ++i) {
    const std::int64_t t = 1'000'000 + i * 100'000;
    const double along = i <= 10 ? i : 20 - i + 0.5;
    turned.truth.push_back({t, {world.start.x_m + along, world.start.y_m, 0.0}});
    // SLAM: the same path in a frame turned by 2 degrees at the start ...
    const double a = 2.0 * std::numbers::pi / 180.0;
    turned.slam_poses.push_back({t, {along * std::cos(a), along * std::sin(a), a}});
    // ... and a path that comes back 1 m to the side of where it went.
    bent.slam_poses.push_back({t, {along, i <= 10 ? 0.0 : 1.0, 0.0}});
  }
  bent.truth = turned.truth;
  const auto free = evaluation::reachable_free_space(world, 0.25, world.start);
  const auto r_turned = make_report("room", turned, world, free, options);
  const auto r_bent = make_report("room", bent, world, free, options);
  ASSERT_TRUE(r_turned.slam_error_aligned_mean_m && r_bent.slam_error_aligned_mean_m);
  EXPECT_GT(*r_turned.slam_error_mean_m, 0.1);
  EXPECT_LT(*r_turned.slam_error_aligned_mean_m, 1e-6);
  EXPECT_GT(*r_bent.slam_error_aligned_mean_m, 0.3);
}

TEST(ExploreReport, UnreadableLogsAreErrors) {
  std::string error;
  EXPECT_FALSE(read_log("/nonexistent/dir/run.lcm", &error));
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;

  TempLog not_a_log;
  std::ofstream(not_a_log.path()) << "this is not an LCM log\n";
  error.clear();
  EXPECT_FALSE(read_log(not_a_log.path(), &error));
  EXPECT_NE(error.find("no LCM event"), std::string::npos) << error;
}

TEST(ExploreReport, PhaseNamesAndJsonStrings) {
  EXPECT_EQ(phase_name(pex::explore_state_t::PHASE_DONE), "done");
  EXPECT_EQ(phase_name(pex::explore_state_t::PHASE_FAILED), "failed");
  EXPECT_EQ(phase_name(pex::explore_state_t::PHASE_STOPPED), "stopped");
  EXPECT_EQ(phase_name(42), "unknown_42");
  Report r;
  r.world = "a\"b\\c\n";
  EXPECT_EQ(to_json(r).rfind("{\"world\":\"a\\\"b\\\\c\\u000a\",\"strategy\":null,", 0), 0u) << to_json(r);
}

}  // namespace
}  // namespace pex::explore_report
