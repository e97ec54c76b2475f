#include "planning/guard_marks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/multi_point.hpp>

#include "archive/byte_archive.hpp"
#include "geometry/point.hpp"
#include "mapping/map_archive.hpp"
#include "planning/keep_out.hpp"
#include "planning/scan_guard.hpp"

namespace pex::planning {

namespace bg = boost::geometry;
using mapping::MultiPolygon;
using mapping::Point;

namespace {
// Below this a hull is a line of returns or one return (m^2, m).
constexpr double kMinHullAreaM2 = 1e-8;
constexpr char kMarksMagic[] = "PEXGMARK";
constexpr std::uint32_t kMarksVersion = 1;
}  // namespace

std::vector<Point> holding_points(std::span<const Point> points_robot_frame, double curvature_per_m,
                                  double body_radius_m, const GuardMarkOptions& options) {
  std::vector<double> free(points_robot_frame.size());
  double least = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < points_robot_frame.size(); ++i) {
    free[i] = free_distance_along_arc(points_robot_frame.subspan(i, 1), curvature_per_m, body_radius_m);
    least = std::min(least, free[i]);
  }
  std::vector<Point> holding;
  if (!(least <= options.max_reach_m)) return holding;
  for (std::size_t i = 0; i < points_robot_frame.size(); ++i)
    if (free[i] <= least + options.holding_depth_m) holding.push_back(points_robot_frame[i]);
  return holding;
}

bool GuardMarks::add(std::span<const Point> holding, const geometry::Pose2& robot, std::int64_t now_utime) {
  if (holding.empty() || !(options_.lifetime_s > 0.0) || options_.max_marks <= 0) return false;
  const geometry::PoseTransform to_map(robot);
  bg::model::multi_point<Point> points;
  for (const Point& p : holding) points.push_back(to_map(p));
  // The hull, not the returns one by one: a pane seen head-on is a line of
  // returns millimetres apart, and the strip over them is one polygon. The
  // hull of returns on a line has no area: its outline, grown, is the strip.
  mapping::Polygon hull;
  bg::convex_hull(points, hull);
  namespace sb = bg::strategy::buffer;
  MultiPolygon area;
  const auto grow = [&](const auto& geometry) {
    bg::buffer(geometry, area, sb::distance_symmetric<double>(0.5 * options_.width_m), sb::side_straight(),
               sb::join_round(8), sb::end_round(8), sb::point_circle(8));
  };
  if (bg::area(hull) > kMinHullAreaM2) {
    grow(hull);
  } else if (bg::perimeter(hull) > kMinHullAreaM2) {
    grow(bg::model::linestring<Point>(hull.outer().begin(), hull.outer().end()));
  } else {
    grow(bg::model::multi_point<Point>{points.front()});
  }
  if (area.empty()) return false;
  marks_.push_back({mapping::with_uniform_type(area, mapping::EdgeType::kObstacle), now_utime});
  if (marks_.size() > static_cast<std::size_t>(options_.max_marks)) marks_.erase(marks_.begin());
  changed_ = true;
  return true;
}

int GuardMarks::expire(std::int64_t now_utime) {
  const auto lifetime_us = static_cast<std::int64_t>(options_.lifetime_s * 1e6);
  const auto old = std::remove_if(marks_.begin(), marks_.end(),
                                  [&](const Mark& m) { return now_utime - m.utime > lifetime_us || m.utime > now_utime; });
  // (A mark made after now comes from a run of another clock.)
  const auto dropped = static_cast<int>(marks_.end() - old);
  marks_.erase(old, marks_.end());
  if (dropped > 0) changed_ = true;
  return dropped;
}

void GuardMarks::clear() {
  if (!marks_.empty()) changed_ = true;
  marks_.clear();
}

std::string GuardMarks::checkpoint() const {
  if (marks_.empty()) return {};
  archive::ByteWriter w;
  w.put<std::uint64_t>(marks_.size());
  for (const Mark& m : marks_) {
    w.put<std::int64_t>(m.utime);
    mapping::write_typed_multipolygon(w, m.area);
  }
  return archive::seal(kMarksMagic, kMarksVersion, w.bytes());
}

std::string GuardMarks::restore(std::string_view checkpoint) {
  std::vector<Mark> restored;
  try {
    const std::string payload = archive::unseal(kMarksMagic, kMarksVersion, checkpoint);
    archive::ByteReader r(payload);
    // A mark is at least its time and an empty polygon list's count.
    const auto n = r.get_count(2 * sizeof(std::uint64_t));
    restored.reserve(n);
    for (std::uint64_t i = 0; i < n; ++i) {
      Mark m;
      m.utime = r.get<std::int64_t>();
      m.area = mapping::read_typed_multipolygon(r, "guard mark " + std::to_string(i));
      restored.push_back(std::move(m));
    }
    r.expect_end();
  } catch (const archive::ArchiveError& e) {
    return e.what();
  }
  const auto keep = static_cast<std::size_t>(std::max(0, options_.max_marks));
  if (restored.size() > keep) restored.erase(restored.begin(), restored.end() - static_cast<std::ptrdiff_t>(keep));
  marks_ = std::move(restored);
  changed_ = true;
  return {};
}

std::shared_ptr<const mapping::TypedMultiPolygon> GuardMarks::with_keep_out(
    const std::shared_ptr<const mapping::TypedMultiPolygon>& keep_out) {
  if (marks_.empty()) return nullptr;
  if (!changed_ && united_keep_out_ == keep_out) return united_;
  std::vector<mapping::TypedMultiPolygon> shapes;
  shapes.reserve(marks_.size() + 1);
  for (const Mark& m : marks_) shapes.push_back(m.area);
  if (keep_out && !keep_out->empty()) shapes.push_back(*keep_out);
  auto united = unite_all(std::move(shapes));
  // An overlay that fails leaves the plans with the operator's keep-out
  // alone: a mark is a hint, the keep-out is not.
  united_ = united.ok ? std::make_shared<const mapping::TypedMultiPolygon>(std::move(united.polygons)) : nullptr;
  united_keep_out_ = keep_out;
  changed_ = false;
  return united_;
}

}  // namespace pex::planning
