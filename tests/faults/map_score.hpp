#pragma once
// A fault test's final map scored against the world, as the exploration
// benchmark scores a run (pex-explore-report's core): a fault must neither
// lose the map nor draw ghost walls or ghost space into it.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <variant>

#include "evaluation/exploration_metrics.hpp"
#include "exploration_set.hpp"
#include "report.hpp"
#include "sim/sim.hpp"

namespace pex::testing {

// The mapper's obstacle band (config/polygon_mapper.toml obstacle_inner_m +
// obstacle_outer_m): on the simulator's zero-thickness walls it takes that
// much floor, which the benchmark's "band credited" columns count as mapped.
inline constexpr double kObstacleBandCreditM = 0.12;

// The set's newest MAP against its world's floor reachable from START.
inline explore_report::Report score_final_map(const ExplorationSet& set) {
  const std::string path = source_path("worlds/" + set.options().world + ".wkt");
  auto parsed = sim::parse_world(read_file(path), path);
  if (const auto* error = std::get_if<sim::WorldError>(&parsed)) {
    ADD_FAILURE() << error->message;
    return {};
  }
  const auto& world = std::get<sim::World>(parsed);
  explore_report::ReportOptions options;
  options.obstacle_band_credit_m = kObstacleBandCreditM;
  // Near the world's walls, not the map's edges: a ghost wall is not credited.
  options.credit_near = evaluation::CreditNear::kWorldWalls;
  // With SLAM the map is in the odometry frame, whose origin is START; on
  // SIM_TRUTH it is in the world frame.
  if (set.options().slam) options.map_in_world = world.start;
  explore_report::LogContents last;
  last.map = set.map();
  last.explore_state = set.state();
  last.sim_clock = set.clock();
  const auto reachable = evaluation::reachable_free_space(world, options.robot_radius_m, world.start);
  return explore_report::make_report(set.options().world, last, world, reachable, options);
}

// The world mapped and nothing else: IoU of the final map with the reachable
// floor (the band credited along the world's walls only) at least 0.95, the
// issue's bound against the fault-free run, taken here against the world
// itself (fault-free two_rooms runs score 0.99: docs/reliability.md). Ghost
// space beyond the walls and ghost walls on the floor both count against it.
inline void expect_map_matches_world(const ExplorationSet& set) {
  ASSERT_TRUE(set.map()) << "no MAP heard";
  const auto report = score_final_map(set);
  ASSERT_TRUE(report.iou && report.coverage) << "the map could not be scored: " << report.map_error;
  std::printf("final map: coverage %.4f, IoU %.4f (band credited along the walls)\n", *report.coverage, *report.iou);
  EXPECT_GE(*report.iou, 0.95) << "the map does not match the world (ghost walls or space, or lost parts)";
}

// The mission runs to its own end: DONE, no collision, the world mapped and
// nothing else (above).
inline void expect_done_with_the_world_mapped(ExplorationSet& set) {
  ASSERT_TRUE(set.spin_to_end()) << set.report_with_logs();
  EXPECT_EQ(set.phase(), +pex::explore_state_t::PHASE_DONE) << set.report_with_logs();
  ASSERT_TRUE(set.clock());
  EXPECT_EQ(set.clock()->collisions, 0) << set.report();
  expect_map_matches_world(set);
}

}  // namespace pex::testing
