#pragma once
// The explorer's adapter between LCM messages and the mission
// (planning/mission.hpp): checked inputs in, BASE_CMD and EXPLORE_STATE out.
// No LCM calls here, so tests can drive it without a bus.
#include <cstdint>
#include <string>

#include <pex/explore_state_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include "explorer_options.hpp"
#include "planning/mission.hpp"

namespace pex::explorer {

struct ExplorerCounters {
  std::int64_t maps_accepted = 0;
  std::int64_t map_polygons_dropped = 0;
  std::int64_t map_rings_reoriented = 0;
  std::int64_t plans = 0;
  std::int64_t goals_reached = 0;
  std::int64_t goals_given_up = 0;
};

class ExplorerNode {
 public:
  explicit ExplorerNode(ExplorerOptions options);

  // Inputs with their arrival time. Return "" when accepted, else why the
  // message was refused (the caller counts it as bad input).
  std::string on_map(const pex::polygon_map_t& msg, std::int64_t now_utime);
  std::string on_pose(const pex::pose_t& msg, std::int64_t now_utime);

  // One control step: the command to publish now.
  pex::velocity_cmd_t step(std::int64_t now_utime);
  // The state after the last step.
  pex::explore_state_t state_message(std::int64_t now_utime) const;
  // A zero command (for shutdown).
  static pex::velocity_cmd_t stop_command(std::int64_t now_utime);

  const planning::MissionOutput& last_output() const { return last_; }
  const ExplorerCounters& counters() const { return counters_; }
  const ExplorerOptions& options() const { return options_; }

 private:
  ExplorerOptions options_;
  planning::Mission mission_;
  planning::MissionOutput last_;
  ExplorerCounters counters_;
};

}  // namespace pex::explorer
