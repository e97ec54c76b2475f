#include "viewer_state.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "geometry/point.hpp"
#include "map_files.hpp"
#include "runtime/daemon_state.hpp"

namespace pex::viewer {

namespace {

using nlohmann::json;

// Coordinates to the millimetre: the page draws them, and the JSON stays short.
double mm(double v) { return std::round(v * 1000.0) / 1000.0; }

bool finite(double v) { return std::isfinite(v); }
// A coordinate no map, pose or goal of ours comes near (1000 km): beyond is garbage.
bool plausible(double v) { return std::isfinite(v) && std::abs(v) < 1e6; }

json points_json(const std::vector<std::pair<double, double>>& points) {
  json out = json::array();
  for (const auto& [x, y] : points) out.push_back({mm(x), mm(y)});
  return out;
}

json rings_json(const pex::polygon_map_t& m) {
  json rings = json::array();
  for (const auto& ring : m.rings) {
    json xs = json::array(), ys = json::array();
    for (double x : ring.x) xs.push_back(mm(x));
    for (double y : ring.y) ys.push_back(mm(y));
    rings.push_back({{"polygon", ring.polygon}, {"hole", ring.hole != 0}, {"x", std::move(xs)}, {"y", std::move(ys)},
                     {"edge_type", ring.edge_type}});
  }
  return rings;
}

bool same_rings(const pex::polygon_map_t& a, const pex::polygon_map_t& b) {
  if (a.rings.size() != b.rings.size()) return false;
  for (std::size_t i = 0; i < a.rings.size(); ++i) {
    const auto &p = a.rings[i], &q = b.rings[i];
    if (p.polygon != q.polygon || p.hole != q.hole || p.x != q.x || p.y != q.y || p.edge_type != q.edge_type)
      return false;
  }
  return true;
}

}  // namespace

const char* phase_name(int phase) {
  static constexpr const char* kNames[] = {"IDLE",   "SELECTING", "MOVING", "DONE",   "FAILED",  "DONE_WITH_UNREACHABLE",
                                           "WAITING_START", "PAUSED", "HOMING", "HOME", "STOPPED"};
  return phase >= 0 && phase < static_cast<int>(std::size(kNames)) ? kNames[phase] : "UNKNOWN";
}

const char* daemon_state_name(int state) { return pex::runtime::daemon_state_name(state); }

ViewerState::ViewerState(ViewerStateOptions options) : options_(options) {}

std::string ViewerState::refusal(const pex::polygon_map_t& map) const {
  if (auto why = map_files::check_map(map); !why.empty()) return why;
  std::int64_t vertices = 0;
  for (const auto& ring : map.rings) vertices += ring.nvertices;
  if (vertices > options_.max_map_vertices)
    return std::to_string(vertices) + " vertices, more than " + std::to_string(options_.max_map_vertices);
  for (const auto& ring : map.rings)
    for (std::size_t i = 0; i < ring.x.size(); ++i)
      if (!plausible(ring.x[i]) || !plausible(ring.y[i])) return "a vertex 1000 km or more away";
  return "";
}

void ViewerState::on_map(const pex::polygon_map_t& map) {
  if (auto why = refusal(map); !why.empty()) throw std::invalid_argument(why);
  map_ = map;
  ++map_version_;
  ++maps_;
}

void ViewerState::on_keep_out(const pex::polygon_map_t& keep_out) {
  if (auto why = refusal(keep_out); !why.empty()) throw std::invalid_argument(why);
  ++keep_outs_;
  // It comes every 5 s unchanged: the page redraws the map only when it changed.
  if (keep_out_ && same_rings(*keep_out_, keep_out)) return;
  keep_out_ = keep_out;
  ++map_version_;
}

void ViewerState::on_pose(const pex::pose_t& pose) {
  if (!plausible(pose.x) || !plausible(pose.y) || !finite(pose.theta))
    throw std::invalid_argument("non-finite or absurd");
  pose_ = pose;
  ++poses_;
  if (trajectory_.empty() || std::hypot(pose.x - trajectory_.back().first, pose.y - trajectory_.back().second) >=
                                 options_.trajectory_min_step_m)
    trajectory_.emplace_back(pose.x, pose.y);
  if (static_cast<int>(trajectory_.size()) > options_.max_trajectory_points) {
    // Every second point goes; the newest stays.
    std::vector<std::pair<double, double>> thinned;
    thinned.reserve(trajectory_.size() / 2 + 1);
    const std::size_t last = trajectory_.size() - 1;
    for (std::size_t i = last % 2; i <= last; i += 2) thinned.push_back(trajectory_[i]);
    trajectory_ = std::move(thinned);
  }
}

void ViewerState::on_scan(const pex::laser_scan_t& scan) {
  if (scan.nranges < 0 || static_cast<std::size_t>(scan.nranges) != scan.ranges.size())
    throw std::invalid_argument("nranges " + std::to_string(scan.nranges) + " but " +
                                std::to_string(scan.ranges.size()) + " ranges");
  if (!finite(scan.angle_min) || !finite(scan.angle_increment) || !finite(scan.range_min) ||
      !finite(scan.range_max) || !finite(scan.sensor_x) || !finite(scan.sensor_y) || !finite(scan.sensor_theta))
    throw std::invalid_argument("non-finite angles, limits or sensor pose");
  if (!pose_) return;  // nothing to draw it from yet: not the scan's fault
  const geometry::Point sensor =
      geometry::transform({pose_->x, pose_->y, pose_->theta}, geometry::Point(scan.sensor_x, scan.sensor_y));
  const double sx = sensor.x(), sy = sensor.y();
  const double st = pose_->theta + scan.sensor_theta;
  const int n = scan.nranges;
  const int step = std::max(1, (n + options_.max_scan_points - 1) / std::max(1, options_.max_scan_points));
  scan_points_.clear();
  for (int i = 0; i < n; i += step) {
    const double r = scan.ranges[static_cast<std::size_t>(i)];
    if (!std::isfinite(r) || r < scan.range_min || r >= scan.range_max) continue;  // no return
    const double a = st + scan.angle_min + i * static_cast<double>(scan.angle_increment);
    scan_points_.emplace_back(sx + r * std::cos(a), sy + r * std::sin(a));
  }
  scan_utime_ = scan.utime;
  ++scans_;
}

void ViewerState::on_explore_state(const pex::explore_state_t& state) {
  const auto npath = static_cast<std::size_t>(std::max(state.npath, 0));
  const auto nfrontiers = static_cast<std::size_t>(std::max(state.nfrontiers, 0));
  if (state.npath < 0 || state.path_x.size() != npath || state.path_y.size() != npath)
    throw std::invalid_argument("npath disagrees with its arrays");
  if (state.nfrontiers < 0 || state.frontier_x.size() != nfrontiers || state.frontier_y.size() != nfrontiers ||
      state.frontier_reason.size() != nfrontiers)
    throw std::invalid_argument("nfrontiers disagrees with its arrays");
  for (std::size_t i = 0; i < npath; ++i)
    if (!plausible(state.path_x[i]) || !plausible(state.path_y[i])) throw std::invalid_argument("non-finite path");
  for (std::size_t i = 0; i < nfrontiers; ++i)
    if (!plausible(state.frontier_x[i]) || !plausible(state.frontier_y[i]))
      throw std::invalid_argument("non-finite frontier");
  if (state.has_goal && (!plausible(state.goal_x) || !plausible(state.goal_y)))
    throw std::invalid_argument("non-finite goal");
  mission_ = state;
  ++states_;
}

void ViewerState::on_status(const pex::daemon_status_t& status, std::int64_t received_utime) {
  const auto n = static_cast<std::size_t>(std::max(status.ncounters, 0));
  if (status.ncounters < 0 || status.counter_names.size() != n || status.counter_values.size() != n)
    throw std::invalid_argument("ncounters disagrees with its arrays");
  if (status.name.empty() || status.name.size() > 64) throw std::invalid_argument("empty or overlong name");
  statuses_[status.name] = {status, received_utime};
  ++statuses_heard_;
}

json ViewerState::map_json() const {
  json out = {{"version", map_version_}};
  out["keep_out"] = keep_out_ ? json{{"utime", keep_out_->utime}, {"rings", rings_json(*keep_out_)}} : json(nullptr);
  if (!map_) return out;
  const auto& m = *map_;
  out["utime"] = m.utime;
  out["frame"] = "map";
  out["particle"] = m.particle;
  out["scans_inserted"] = m.scans_inserted;
  out["vertex_count"] = m.vertex_count;
  out["free_area_m2"] = m.free_area_m2;
  out["obstacle_length_m"] = m.obstacle_length_m;
  out["frontier_length_m"] = m.frontier_length_m;
  out["rings"] = rings_json(m);
  return out;
}

json ViewerState::live_json(std::int64_t now_utime) const {
  json out = {{"utime", now_utime}, {"map_version", map_version_}};
  out["pose"] = pose_ ? json{{"utime", pose_->utime}, {"x", mm(pose_->x)}, {"y", mm(pose_->y)},
                             {"theta", std::round(pose_->theta * 1e4) / 1e4}}
                      : json(nullptr);
  out["trajectory"] = points_json(trajectory_);
  out["scan"] = scan_utime_ ? json{{"utime", *scan_utime_}, {"points", points_json(scan_points_)}} : json(nullptr);
  if (mission_) {
    const auto& s = *mission_;
    std::vector<std::pair<double, double>> path;
    for (std::size_t i = 0; i < s.path_x.size(); ++i) path.emplace_back(s.path_x[i], s.path_y[i]);
    json frontiers = json::array();
    for (std::size_t i = 0; i < s.frontier_x.size(); ++i)
      frontiers.push_back({{"x", mm(s.frontier_x[i])}, {"y", mm(s.frontier_y[i])}, {"reason", s.frontier_reason[i]}});
    out["mission"] = {{"utime", s.utime},
                      {"phase", s.phase},
                      {"phase_name", phase_name(s.phase)},
                      {"status", s.status},
                      {"strategy", s.strategy},
                      {"goal", s.has_goal ? json{{"x", mm(s.goal_x)}, {"y", mm(s.goal_y)}} : json(nullptr)},
                      {"goal_candidates", s.goal_candidates},
                      {"path", points_json(path)},
                      {"frontiers", std::move(frontiers)},
                      {"explored_area_m2", s.explored_area_m2},
                      {"distance_travelled_m", s.distance_travelled_m},
                      {"mission_time_s", s.mission_time_s},
                      {"goals_reached", s.goals_reached},
                      {"goals_given_up", s.goals_given_up},
                      {"plans", s.plans}};
  } else {
    out["mission"] = nullptr;
  }
  json daemons = json::array();
  for (const auto& [name, st] : statuses_) {
    const auto& m = st.msg;
    const double age_s = static_cast<double>(now_utime - st.received_utime) * 1e-6;
    daemons.push_back({{"name", name},
                       {"state", m.state},
                       {"state_name", daemon_state_name(m.state)},
                       {"pid", m.pid},
                       {"uptime_s", m.uptime_s},
                       {"msgs_in", m.msgs_in},
                       {"msgs_out", m.msgs_out},
                       {"msgs_rejected", m.msgs_rejected},
                       {"errors", m.errors},
                       {"last_error", m.last_error},
                       {"age_s", std::round(age_s * 10.0) / 10.0},
                       {"stale", age_s > options_.status_stale_s}});
  }
  out["daemons"] = std::move(daemons);
  out["counts"] = {{"maps", maps_}, {"keep_outs", keep_outs_}, {"poses", poses_}, {"scans", scans_}, {"states", states_},
                   {"statuses", statuses_heard_}};
  return out;
}

json ViewerState::state_json(std::int64_t now_utime) const {
  json out = live_json(now_utime);
  out["map"] = map_json();
  return out;
}

}  // namespace pex::viewer
