#pragma once
// What pex-viewer shows, kept from the bus's messages and written as JSON for
// the page (/api/state, /events): the map, the robot, its trajectory, the
// current scan, the mission (goal, path, frontier candidates, progress),
// the explorer's keep-out lines and areas (KEEP_OUT) and the daemons' health. No LCM, no clock, no I/O: the daemon passes messages
// and times in (viewer_state_test.cpp).
//
// Every on_*() checks the message first and returns why it refuses it; a
// refused message changes nothing, so the page keeps the last good state.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>

namespace pex::viewer {

struct ViewerStateOptions {
  std::int64_t max_map_vertices = 200'000;  // a larger MAP is refused (oversize)
  double trajectory_min_step_m = 0.05;      // a pose this far from the last point extends the trajectory
  int max_trajectory_points = 5000;         // beyond, every second point of the trajectory is dropped
  int max_scan_points = 1081;               // the scan's returns, thinned evenly to at most this many
  double status_stale_s = 3.0;              // a daemon not heard from this long is shown stale
};

// The name the page shows for an explore_state_t phase ("MOVING"); "UNKNOWN" for others.
const char* phase_name(int phase);
// The name of a daemon_status_t state ("OK"); "UNKNOWN" for others.
const char* daemon_state_name(int state);

class ViewerState {
 public:
  explicit ViewerState(ViewerStateOptions options = {});

  // A message refused throws std::invalid_argument with the reason and
  // changes nothing; the daemon's log line names the channel.
  void on_map(const pex::polygon_map_t& map);
  // KEEP_OUT: the explorer's keep-out polygons in the map frame, checked as a MAP is.
  void on_keep_out(const pex::polygon_map_t& keep_out);
  void on_pose(const pex::pose_t& pose);
  // The scan is drawn from the newest pose (ignored before the first).
  void on_scan(const pex::laser_scan_t& scan);
  void on_explore_state(const pex::explore_state_t& state);
  // `received_utime`: when the viewer heard it, on the clock later passed to live_json().
  void on_status(const pex::daemon_status_t& status, std::int64_t received_utime);

  // Bumped by every accepted MAP and by a KEEP_OUT that differs from the
  // last: a page needs map_json() again only when it changed.
  std::int64_t map_version() const { return map_version_; }
  // The map: {"version", "utime", "frame", "free_area_m2", ..., "rings": [{"polygon",
  // "hole", "x": [...], "y": [...], "edge_type": [0 obstacle | 1 frontier, ...]}],
  // "keep_out": {"utime", "rings": [as the map's]} or null}.
  nlohmann::json map_json() const;
  // Everything but the map, at `now_utime`: "pose", "trajectory", "scan",
  // "mission", "daemons" (sorted by name, with "age_s" and "stale"), "counts".
  nlohmann::json live_json(std::int64_t now_utime) const;
  // /api/state: live_json() with the map under "map".
  nlohmann::json state_json(std::int64_t now_utime) const;

  const std::vector<std::pair<double, double>>& trajectory() const { return trajectory_; }

 private:
  struct Status {
    pex::daemon_status_t msg;
    std::int64_t received_utime = 0;
  };
  ViewerStateOptions options_;
  // Why `map` (a MAP or a KEEP_OUT) is refused; "" when it is fine.
  std::string refusal(const pex::polygon_map_t& map) const;
  std::optional<pex::polygon_map_t> map_;
  std::optional<pex::polygon_map_t> keep_out_;
  std::int64_t map_version_ = 0;
  std::optional<pex::pose_t> pose_;
  std::vector<std::pair<double, double>> trajectory_;
  std::optional<std::int64_t> scan_utime_;
  std::vector<std::pair<double, double>> scan_points_;  // map frame, m
  std::optional<pex::explore_state_t> mission_;
  std::map<std::string, Status> statuses_;
  std::int64_t maps_ = 0, keep_outs_ = 0, poses_ = 0, scans_ = 0, states_ = 0, statuses_heard_ = 0;
};

}  // namespace pex::viewer
