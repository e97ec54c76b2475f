#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <numbers>
#include <sstream>

#include <lcm/lcm-cpp.hpp>
#include <pex/pose_t.hpp>

#include "geometry/rigid_fit.hpp"
#include "map_message.hpp"
#include "planning/mission.hpp"
#include "runtime/channels.hpp"

namespace pex::explore_report {

namespace bg = boost::geometry;
using mapping::MultiPolygon;

namespace {

template <class Msg>
bool decode(const lcm::LogEvent& event, Msg& msg) {
  return msg.decode(event.data, 0, event.datalen) == event.datalen;
}

std::optional<std::int64_t> counter(const pex::daemon_status_t& status, const std::string& name) {
  for (int i = 0; i < status.ncounters && i < static_cast<int>(status.counter_names.size()); ++i)
    if (status.counter_names[static_cast<std::size_t>(i)] == name) return status.counter_values[static_cast<std::size_t>(i)];
  return std::nullopt;
}

std::optional<double> us_to_ms(std::optional<std::int64_t> us) {
  if (!us) return std::nullopt;
  return static_cast<double>(*us) / 1000.0;
}

std::optional<double> finite(double v) {
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

// Report's slam_error_*, from the pose pairs.
void audit_poses(const LogContents& log, const geometry::Pose2& map_in_world, Report& r) {
  const std::vector<PoseError> pairs = pose_errors(log, map_in_world);
  if (pairs.empty()) return;
  double sum = 0.0, worst = 0.0, heading_sum = 0.0;
  std::vector<geometry::Point> placed, true_points;  // the pairs compared
  for (const PoseError& pair : pairs) {
    sum += pair.error_m;
    worst = std::max(worst, pair.error_m);
    heading_sum += std::abs(pair.heading_error_rad);
    placed.emplace_back(pair.slam_in_world.x_m, pair.slam_in_world.y_m);
    true_points.emplace_back(pair.truth.x_m, pair.truth.y_m);
  }
  const auto n = static_cast<double>(pairs.size());
  r.slam_error_mean_m = sum / n;
  r.slam_error_max_m = worst;
  r.slam_heading_error_mean_deg = heading_sum / n * 180.0 / std::numbers::pi;
  // The same after the best rigid motion of the whole trajectory (the
  // absolute trajectory error as SLAM benchmarks state it): what is left is
  // the map bending, not its frame turned at the start.
  if (const auto fit = geometry::best_rigid_fit(placed, true_points)) {
    const geometry::PoseTransform align(*fit);
    double aligned_sum = 0.0;
    for (std::size_t i = 0; i < placed.size(); ++i) {
      const geometry::Point p = align(placed[i]);
      aligned_sum += std::hypot(p.x() - true_points[i].x(), p.y() - true_points[i].y());
    }
    r.slam_error_aligned_mean_m = aligned_sum / n;
  }
}

}  // namespace

std::vector<PoseError> pose_errors(const LogContents& log, const geometry::Pose2& map_in_world) {
  std::vector<PoseError> out;
  if (log.slam_poses.empty() || log.truth.empty()) return out;
  std::vector<StampedPose> truth = log.truth;
  std::stable_sort(truth.begin(), truth.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });
  for (const auto& slam : log.slam_poses) {
    auto it = std::lower_bound(truth.begin(), truth.end(), slam.utime,
                               [](const StampedPose& p, std::int64_t t) { return p.utime < t; });
    const StampedPose* nearest = nullptr;
    if (it != truth.end()) nearest = &*it;
    if (it != truth.begin() && (!nearest || slam.utime - std::prev(it)->utime < nearest->utime - slam.utime))
      nearest = &*std::prev(it);
    if (!nearest || std::llabs(nearest->utime - slam.utime) > 20'000) continue;
    PoseError pair;
    pair.utime = slam.utime;
    pair.slam_in_world = geometry::compose(map_in_world, slam.pose);
    pair.truth = nearest->pose;
    pair.error_m = std::hypot(pair.slam_in_world.x_m - pair.truth.x_m, pair.slam_in_world.y_m - pair.truth.y_m);
    if (!std::isfinite(pair.error_m)) continue;
    pair.heading_error_rad = geometry::wrap_angle(pair.slam_in_world.theta_rad - pair.truth.theta_rad);
    out.push_back(pair);
  }
  return out;
}

std::optional<LogContents> read_log(const std::string& path, std::string* error) {
  lcm::LogFile log(path, "r");
  if (!log.good()) {
    if (error) *error = "cannot open LCM log " + path;
    return std::nullopt;
  }
  namespace ch = runtime::channels;
  LogContents out;
  for (const lcm::LogEvent* event = log.readNextEvent(); event; event = log.readNextEvent()) {
    ++out.events;
    if (event->channel == ch::kMap || event->channel == ch::kMapFree) {
      pex::polygon_map_t msg;
      if (!decode(*event, msg)) ++out.rejected;
      else (event->channel == ch::kMap ? out.map : out.free_space) = std::move(msg);
    } else if (event->channel == ch::kExploreState) {
      pex::explore_state_t msg;
      if (decode(*event, msg)) out.explore_state = std::move(msg); else ++out.rejected;
    } else if (event->channel == ch::kSimClock) {
      pex::sim_clock_t msg;
      if (decode(*event, msg)) out.sim_clock = msg; else ++out.rejected;
    } else if (event->channel == ch::kSlamPose || event->channel == ch::kSimTruth) {
      pex::pose_t msg;
      if (!decode(*event, msg)) ++out.rejected;
      else (event->channel == ch::kSlamPose ? out.slam_poses : out.truth)
          .push_back({msg.utime, geometry::Pose2{msg.x, msg.y, msg.theta}});
    } else if (event->channel == ch::kDaemonStatus) {
      pex::daemon_status_t msg;
      if (!decode(*event, msg)) ++out.rejected;
      else if (msg.name == "explorer") out.explorer_status = std::move(msg);
    }
  }
  if (out.events == 0) {
    if (error) *error = "no LCM event in " + path + " (empty, or not an LCM log)";
    return std::nullopt;
  }
  return out;
}

std::string phase_name(std::int8_t phase) {
  using S = pex::explore_state_t;
  switch (phase) {
    case S::PHASE_IDLE: return "idle";
    case S::PHASE_SELECTING: return "selecting";
    case S::PHASE_MOVING: return "moving";
    case S::PHASE_DONE: return "done";
    case S::PHASE_FAILED: return "failed";
    case S::PHASE_DONE_WITH_UNREACHABLE: return "done_with_unreachable";
    case S::PHASE_WAITING_START: return "waiting_start";
    case S::PHASE_PAUSED: return "paused";
    case S::PHASE_HOMING: return "homing";
    case S::PHASE_HOME: return "home";
    case S::PHASE_STOPPED: return "stopped";
    default: return "unknown_" + std::to_string(static_cast<int>(phase));
  }
}

Report make_report(const std::string& world_name, const LogContents& log, const sim::World& world,
                   const MultiPolygon& reachable, const ReportOptions& options,
                   mapping::TypedMultiPolygon* map_world, const MultiPolygon* world_free) {
  Report r;
  r.world = world_name;
  r.reachable_m2 = bg::area(reachable);
  if (const auto& s = log.explore_state) {
    if (!s->strategy.empty()) r.strategy = s->strategy;
    r.phase = phase_name(s->phase);
    r.path_m = s->distance_travelled_m;
    r.goals = s->goals_reached;
    r.plans = s->plans;
  }
  if (log.sim_clock) {
    r.sim_time_s = static_cast<double>(log.sim_clock->sim_time_us) / 1e6;
    r.collisions = log.sim_clock->collisions;
  } else if (log.explore_state) {
    r.sim_time_s = log.explore_state->mission_time_s;
  }
  if (const auto& st = log.explorer_status) {
    r.plan_ms_p50 = us_to_ms(counter(*st, "plan_us_p50"));
    r.plan_ms_p99 = us_to_ms(counter(*st, "plan_us_p99"));
    r.control_ms_p99 = us_to_ms(counter(*st, "control_us_p99"));
    r.plan_cpu_ms_p50 = us_to_ms(counter(*st, "plan_cpu_us_p50"));
    r.plan_cpu_ms_p99 = us_to_ms(counter(*st, "plan_cpu_us_p99"));
    for (int k = 0; k < planning::kPlanKinds; ++k) {
      const std::string kind = planning::to_string(static_cast<planning::PlanKind>(k));
      const auto plans = counter(*st, "plans_" + kind);
      if (plans) r.plans_by_kind.push_back({kind, plans, us_to_ms(counter(*st, "plan_cpu_us_p99_" + kind))});
    }
    r.goals_seen = counter(*st, "goals_seen");
    const auto blocked = counter(*st, "goals_blocked"), no_progress = counter(*st, "goals_no_progress");
    // goals_overdue and goals_came_back are newer: before the first,
    // goals_no_progress counted those too; before the second, none was.
    const auto overdue = counter(*st, "goals_overdue"), came_back = counter(*st, "goals_came_back");
    if (blocked && no_progress)
      r.goals_given_up = *blocked + *no_progress + overdue.value_or(0) + came_back.value_or(0);
  }
  audit_poses(log, options.map_in_world, r);
  const bool free_space = options.scored_map == ScoredMap::kFreeSpace ||
                          (options.scored_map == ScoredMap::kAuto && log.free_space.has_value());
  const auto& scored = free_space ? log.free_space : log.map;
  if (scored) {
    r.scored_map = std::string(free_space ? runtime::channels::kMapFree : runtime::channels::kMap);
    explorer::MapDecodeOptions decode_options;
    decode_options.max_vertices = std::numeric_limits<std::int64_t>::max();  // score whatever was published
    const auto decoded = explorer::decode_map(*scored, decode_options);
    if (!decoded.ok) {
      r.map_error = decoded.error;
    } else {
      r.map_polygons_dropped = decoded.polygons_dropped;
      const evaluation::WallIndex walls(world.walls);
      const auto score =
          evaluation::score_map(decoded.polygons, options.map_in_world, reachable, walls, options.wall_tolerance_m,
                                options.obstacle_band_credit_m, options.credit_near);
      r.explored_m2 = score.explored_m2;
      r.coverage = finite(score.coverage);
      r.iou = finite(score.iou);
      r.obstacle_on_wall = finite(score.obstacle_on_wall);
      if (map_world || world_free) {
        auto typed_world = evaluation::to_world(decoded.polygons, options.map_in_world);
        if (world_free) {
          const MultiPolygon map_free = mapping::geometry_of(typed_world);
          if (const auto outside = evaluation::checked_overlay(map_free, *world_free, mapping::OverlayOp::kDifference)) {
            r.map_outside_free_m2 = bg::area(*outside);
            r.map_unreachable_free_m2 =
                std::max(0.0, score.explored_m2 - *r.map_outside_free_m2 - score.mapped_reachable_m2);
          }
        }
        if (map_world) *map_world = std::move(typed_world);
      }
    }
  }
  return r;
}

namespace {

class JsonLine {
 public:
  void key(const char* k) {
    out_ << (first_ ? "{" : ",") << '"' << k << "\":";
    first_ = false;
  }
  void string(const char* k, const std::optional<std::string>& v) {
    key(k);
    if (!v) {
      out_ << "null";
      return;
    }
    out_ << '"';
    for (const char c : *v) {
      if (c == '"' || c == '\\') out_ << '\\' << c;
      else if (static_cast<unsigned char>(c) < 0x20) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
        out_ << buf;
      } else out_ << c;
    }
    out_ << '"';
  }
  void number(const char* k, const std::optional<double>& v, int decimals) {
    key(k);
    if (!v || !std::isfinite(*v)) {
      out_ << "null";
      return;
    }
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, *v);
    out_ << buf;
  }
  void integer(const char* k, const std::optional<std::int64_t>& v) {
    key(k);
    if (v) out_ << *v; else out_ << "null";
  }
  std::string str() const { return out_.str() + "}"; }

 private:
  std::ostringstream out_;
  bool first_ = true;
};

}  // namespace

std::string to_json(const Report& r) {
  JsonLine j;
  j.string("world", r.world);
  j.string("strategy", r.strategy);
  j.string("phase", r.phase);
  j.number("sim_time_s", r.sim_time_s, 3);
  j.number("path_m", r.path_m, 3);
  j.number("explored_m2", r.explored_m2, 3);
  j.number("reachable_m2", r.reachable_m2, 3);
  j.number("coverage", r.coverage, 5);
  j.number("iou", r.iou, 5);
  j.number("obstacle_on_wall", r.obstacle_on_wall, 5);
  j.integer("collisions", r.collisions);
  j.integer("goals", r.goals);
  j.integer("plans", r.plans);
  j.number("plan_ms_p50", r.plan_ms_p50, 3);
  j.number("plan_ms_p99", r.plan_ms_p99, 3);
  j.number("control_ms_p99", r.control_ms_p99, 3);
  j.number("plan_cpu_ms_p50", r.plan_cpu_ms_p50, 3);
  j.number("plan_cpu_ms_p99", r.plan_cpu_ms_p99, 3);
  for (const auto& k : r.plans_by_kind) {
    j.integer(("plans_" + k.kind).c_str(), k.plans);
    j.number(("plan_cpu_ms_p99_" + k.kind).c_str(), k.cpu_ms_p99, 3);
  }
  j.number("map_outside_free_m2", r.map_outside_free_m2, 3);
  j.number("map_unreachable_free_m2", r.map_unreachable_free_m2, 3);
  j.number("slam_error_mean_m", r.slam_error_mean_m, 3);
  j.number("slam_error_max_m", r.slam_error_max_m, 3);
  j.number("slam_heading_error_mean_deg", r.slam_heading_error_mean_deg, 2);
  j.number("slam_error_aligned_mean_m", r.slam_error_aligned_mean_m, 3);
  j.string("scored_map", r.scored_map);
  j.integer("goals_seen", r.goals_seen);
  j.integer("goals_given_up", r.goals_given_up);
  return j.str();
}

namespace {

// SVG path data of polygons (each ring a closed subpath) in the drawing's
// pixel frame; the fill rule even-odd keeps holes empty.
template <class ToPx>
std::string path_of(const MultiPolygon& polygons, const ToPx& px) {
  std::ostringstream d;
  auto ring = [&](const mapping::Ring& points) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto [x, y] = px(points[i]);
      d << (i == 0 ? "M" : "L") << x << ' ' << y << ' ';
    }
    d << "Z ";
  };
  for (const auto& p : polygons) {
    ring(p.outer());
    for (const auto& h : p.inners()) ring(h);
  }
  return d.str();
}

}  // namespace

std::string to_svg(const sim::World& world, const MultiPolygon& reachable, const mapping::TypedMultiPolygon& map_world,
                   const geometry::Pose2& start, double robot_radius_m, double wall_tolerance_m,
                   const MultiPolygon* world_free) {
  const MultiPolygon map_free = mapping::geometry_of(map_world);
  // Frame: the walls' box and the map, a 1 m margin.
  double min_x = world.min_x, min_y = world.min_y, max_x = world.max_x, max_y = world.max_y;
  mapping::for_each_edge(map_world, [&](const mapping::Point& a, const mapping::Point&, mapping::EdgeType) {
    min_x = std::min(min_x, a.x()), max_x = std::max(max_x, a.x());
    min_y = std::min(min_y, a.y()), max_y = std::max(max_y, a.y());
  });
  const double margin = 1.0;
  const double x0 = min_x - margin, y1 = max_y + margin;
  const double width_m = max_x - min_x + 2 * margin, height_m = max_y - min_y + 2 * margin;
  const double scale = std::min(40.0, 1600.0 / std::max(width_m, height_m));  // px per m
  auto px = [&](const mapping::Point& p) {
    return std::pair<long, long>(std::lround((p.x() - x0) * scale * 10), std::lround((y1 - p.y()) * scale * 10));
  };  // tenths of a pixel, as integers: short and exact; the viewBox scales back

  const auto missed = evaluation::checked_overlay(reachable, map_free, mapping::OverlayOp::kDifference);
  const auto outside = evaluation::checked_overlay(map_free, reachable, mapping::OverlayOp::kDifference);

  std::ostringstream s;
  const long w_px = std::lround(width_m * scale), h_px = std::lround(height_m * scale);
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w_px << "\" height=\"" << h_px << "\" viewBox=\"0 0 "
    << w_px * 10 << ' ' << h_px * 10 << "\">\n";
  s << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  s << "<path fill=\"#bfe8bf\" fill-rule=\"evenodd\" d=\"" << path_of(reachable, px) << "\"/>\n";
  s << "<path fill=\"#4a78c8\" fill-opacity=\"0.55\" fill-rule=\"evenodd\" d=\"" << path_of(map_free, px) << "\"/>\n";
  if (missed) s << "<path fill=\"#e03030\" fill-rule=\"evenodd\" d=\"" << path_of(*missed, px) << "\"/>\n";
  if (outside) s << "<path fill=\"#a040c0\" fill-rule=\"evenodd\" d=\"" << path_of(*outside, px) << "\"/>\n";
  if (world_free) {
    if (const auto beyond = evaluation::checked_overlay(map_free, *world_free, mapping::OverlayOp::kDifference))
      s << "<path fill=\"#e0a000\" fill-rule=\"evenodd\" d=\"" << path_of(*beyond, px) << "\"/>\n";
  }
  const double edge_px = std::max(10.0, 0.05 * scale * 10);
  // Map edges: obstacle edges on a wall (within wall_tolerance_m for at
  // least 99 % of their length) dark blue, off the walls magenta; frontiers orange.
  const evaluation::WallIndex walls(world.walls);
  std::ostringstream on_wall, off_wall, frontier;
  mapping::for_each_edge(map_world, [&](const mapping::Point& a, const mapping::Point& b, mapping::EdgeType t) {
    const auto [ax, ay] = px(a);
    const auto [bx, by] = px(b);
    std::ostringstream& d = t != mapping::EdgeType::kObstacle ? frontier
                            : walls.length_near_walls(a, b, wall_tolerance_m) >= 0.99 * bg::distance(a, b) ? on_wall
                                                                                                         : off_wall;
    d << 'M' << ax << ' ' << ay << 'L' << bx << ' ' << by << ' ';
  });
  for (const auto& [d, colour] : {std::pair{&on_wall, "#102060"}, std::pair{&off_wall, "#ff00ff"},
                                  std::pair{&frontier, "#ff9900"}})
    s << "<path fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"" << edge_px << "\" d=\"" << d->str()
      << "\"/>\n";
  {
    std::ostringstream d;
    for (const auto& wall : world.walls) {
      const auto [ax, ay] = px(mapping::Point(wall.x0, wall.y0));
      const auto [bx, by] = px(mapping::Point(wall.x1, wall.y1));
      d << 'M' << ax << ' ' << ay << 'L' << bx << ' ' << by << ' ';
    }
    s << "<path fill=\"none\" stroke=\"black\" stroke-width=\"" << edge_px * 0.6 << "\" stroke-linecap=\"round\" d=\""
      << d.str() << "\"/>\n";
  }
  const auto [sx, sy] = px(mapping::Point(start.x_m, start.y_m));
  s << "<circle cx=\"" << sx << "\" cy=\"" << sy << "\" r=\"" << robot_radius_m * scale * 10
    << "\" fill=\"none\" stroke=\"#008000\" stroke-width=\"" << edge_px << "\"/>\n";
  s << "</svg>\n";
  return s.str();
}

}  // namespace pex::explore_report
