#pragma once
// The explorer daemon's options: every key of config/explorer.toml, read in
// one place into the planning library's option structs.
#include <cstddef>
#include <memory>
#include <string>

#include "map_message.hpp"
#include "planning/mission.hpp"
#include "planning/live_view.hpp"
#include "planning/guard_marks.hpp"
#include "planning/scan_guard.hpp"

namespace pex::runtime {
class ConfigReader;
}

namespace pex::explorer {

struct ExplorerOptions {
  std::string pose_channel = "SLAM_POSE";  // a registered pex.pose_t channel (SIM_TRUTH for tests)
  double cmd_rate_hz = 10.0;               // BASE_CMD rate (the mission steps at this rate)
  double state_rate_hz = 2.0;              // EXPLORE_STATE rate
  // The mission's checkpoint (planning::MissionCheckpoint), written every
  // checkpoint_period_s and on stop, read at start: "" = none.
  std::string checkpoint_file;
  double checkpoint_period_s = 2.0;
  // The way the robot drove (TrailKeeper's checkpoint), written with the same
  // period: "" = none, and a restarted explorer's tight plans have no trail
  // until the robot has driven again.
  std::string trail_checkpoint_file;
  MapDecodeOptions map;
  planning::MissionOptions mission;
  // The live scan bounds the forward speed (planning/scan_guard.hpp); off: the map alone.
  bool scan_guard = true;
  planning::ScanGuardOptions guard;
  planning::GuardScanOptions guard_scan;  // how the guard reads a scan (wall ends, corners)
  // The guard holding the robot still this long (the follower wants to drive
  // on) is a guard block: the mission replans round it and starts the goal's
  // progress anew (Mission::on_guard_block). 0: not told.
  std::int64_t guard_block_us = 1'000'000;
  // What held the robot in a guard block is kept out of the plans for a
  // while (planning/guard_marks.hpp); lifetime 0: no marks.
  planning::GuardMarkOptions guard_marks;
  std::size_t max_beams = 8192;           // a LIDAR_SCAN with more beams is refused as bad input
  // A LIDAR_SCAN with fewer returns is refused as no view (a laser covered
  // or dazzled): it keeps no scan fresh, so the robot stops as without
  // scans. 0: off.
  int min_scan_returns = 0;
  // The newest scan opens the planning map near the robot (planning/live_view.hpp).
  planning::LiveViewOptions live_view;
  // ... only for the plans the map alone gives no way (PlanRequest::live_view_when_stuck_only).
  bool live_view_when_stuck_only = true;
  // Beams blind (no echo at the planning map's walls within guard_map_walls_m,
  // scan after scan) open nothing in the live view (mapping/blind_beams.hpp).
  mapping::BlindBeamOptions blind_beams;
  // Keep-out lines and areas (planning/keep_out.hpp) from keep_out_file, in
  // the map frame; null: none. Every plan treats them as walls.
  std::shared_ptr<const mapping::TypedMultiPolygon> keep_out;
  int keep_out_lines = 0, keep_out_areas = 0;  // read from the file, for the log
};

// Reads and validates every key; throws runtime::ConfigError on a bad value.
ExplorerOptions load_options(runtime::ConfigReader& config);

}  // namespace pex::explorer
