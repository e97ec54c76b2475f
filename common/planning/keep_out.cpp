#include "planning/keep_out.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <vector>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/linestring.hpp>
#include <boost/geometry/geometries/multi_linestring.hpp>

#include "geometry/point.hpp"
#include "geometry/wkt_text.hpp"
#include "mapping/typed_ops.hpp"

namespace pex::planning {

namespace bg = boost::geometry;
using geometry::Point;
using mapping::MultiPolygon;
using mapping::Polygon;
using Linestring = bg::model::linestring<Point>;
using MultiLinestring = bg::model::multi_linestring<Linestring>;

namespace {

using geometry::leading_keyword;
using geometry::trim_blanks;

bool coordinates_ok(const auto& shape) {
  bool ok = true;
  bg::for_each_point(shape, [&](const Point& p) { ok = ok && geometry::file_coordinates_ok(p.x(), p.y()); });
  return ok;
}

// A polyline (map frame) as a strip `width` wide: flat at its ends, which
// stay where they were drawn (a line drawn up to a door's jamb narrows no
// door), round at its corners.
MultiPolygon strip(const Linestring& line, double width) {
  namespace sb = bg::strategy::buffer;
  MultiPolygon out;
  bg::buffer(line, out, sb::distance_symmetric<double>(0.5 * width), sb::side_straight(), sb::join_round(8),
             sb::end_flat(), sb::point_circle(8));
  return out;
}

}  // namespace

// Every shape united by the map's own overlay (typed_union, which checks
// its result), pairwise: a balanced tree of unions, in which each vertex
// takes part in about log2(n) of them. Boost's union_ of a few thousand
// strips one at a time came out invalid (the walls of worlds/intel.wkt as
// 3452 lines: nested interior rings), and the overlay of every plan then
// refused it.
mapping::TypedOpResult unite_all(std::vector<mapping::TypedMultiPolygon> shapes) {
  while (shapes.size() > 1) {
    std::vector<mapping::TypedMultiPolygon> next;
    for (std::size_t i = 0; i + 1 < shapes.size(); i += 2) {
      auto pair = mapping::typed_union(shapes[i], shapes[i + 1]);
      if (!pair.ok) return pair;
      next.push_back(std::move(pair.polygons));
    }
    if (shapes.size() % 2 == 1) next.push_back(std::move(shapes.back()));
    shapes = std::move(next);
  }
  mapping::TypedOpResult out;
  out.ok = true;
  if (!shapes.empty()) out.polygons = std::move(shapes.front());
  return out;
}

std::variant<KeepOut, KeepOutError> parse_keep_out(std::string_view text, const std::string& origin,
                                                   const geometry::Pose2& start_in_file, double line_width_m) {
  KeepOut out;
  const geometry::PoseTransform to_map(geometry::inverse(start_in_file));
  std::vector<mapping::TypedMultiPolygon> shapes;  // united at the end
  std::string shape_error;
  auto unite = [&](const MultiPolygon& shape) {
    shapes.push_back(mapping::with_uniform_type(shape, mapping::EdgeType::kObstacle));
    std::string why;
    if (!mapping::is_valid(shapes.back(), &why)) shape_error = "not a valid area once in the map frame: " + why;
  };
  // The map's overlay takes coordinates up to kOverlayMaxCoordinateM: a
  // keep-out beyond it in the map frame would fail every plan. 1 m in from
  // it, a strip's side (half a line's width) stays within.
  const double reach_m = mapping::kOverlayMaxCoordinateM - 1.0;
  const std::string too_far = "beyond " + std::to_string(static_cast<int>(reach_m)) +
                              " m of the robot's start in the map frame (the map's extent): is the start pose right?";
  auto in_reach = [&](const Point& q) { return std::abs(q.x()) <= reach_m && std::abs(q.y()) <= reach_m; };
  auto add = [&](Polygon p) -> std::string {
    for (Point& q : p.outer()) q = to_map(q);
    for (auto& inner : p.inners())
      for (Point& q : inner) q = to_map(q);
    if (!std::all_of(p.outer().begin(), p.outer().end(), in_reach)) return too_far;
    bg::correct(p);
    unite(MultiPolygon{p});
    return shape_error;
  };
  auto add_line = [&](const Linestring& drawn) -> std::string {
    Linestring line;
    for (const Point& q : drawn)
      if (line.empty() || !bg::equals(line.back(), to_map(q))) line.push_back(to_map(q));
    if (!std::all_of(line.begin(), line.end(), in_reach)) return too_far;
    if (line.size() < 2) return "";
    unite(strip(line, line_width_m));
    out.lines += static_cast<int>(line.size()) - 1;
    return shape_error;
  };
  auto add_area = [&](const Polygon& polygon) -> std::string {
    if (auto open = geometry::unclosed_ring(polygon); !open.empty()) return open;
    Polygon p = polygon;
    bg::correct(p);
    if (!bg::is_valid(p)) return "POLYGON is not a valid area (a ring crossing itself?)";
    if (auto far = add(std::move(p)); !far.empty()) return far;
    ++out.areas;
    return "";
  };
  int line_number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string line = trim_blanks(text.substr(pos, end - pos));
    pos = end + 1;
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    auto fail = [&](const std::string& what) {
      return KeepOutError{origin + ":" + std::to_string(line_number) + ": " + what};
    };
    const std::string keyword = leading_keyword(line);
    try {
      std::string error;
      if (keyword == "LINESTRING") {
        Linestring g;
        bg::read_wkt(line, g);
        if (!coordinates_ok(g)) return fail(geometry::kBadFileCoordinate);
        error = add_line(g);
      } else if (keyword == "MULTILINESTRING") {
        MultiLinestring g;
        bg::read_wkt(line, g);
        if (!coordinates_ok(g)) return fail(geometry::kBadFileCoordinate);
        for (const auto& l : g)
          if (error.empty()) error = add_line(l);
      } else if (keyword == "POLYGON") {
        Polygon g;
        bg::read_wkt(line, g);
        if (!coordinates_ok(g)) return fail(geometry::kBadFileCoordinate);
        error = add_area(g);
      } else if (keyword == "MULTIPOLYGON") {
        MultiPolygon g;
        bg::read_wkt(line, g);
        if (!coordinates_ok(g)) return fail(geometry::kBadFileCoordinate);
        for (const auto& p : g)
          if (error.empty()) error = add_area(p);
      } else {
        return fail("unsupported geometry '" + keyword.substr(0, 24) +
                    "' (one LINESTRING, MULTILINESTRING, POLYGON or MULTIPOLYGON per line)");
      }
      if (!error.empty()) return fail(error);
    } catch (const std::exception& e) {
      return fail(std::string("bad WKT: ") + e.what());
    }
  }
  auto united = unite_all(std::move(shapes));
  if (!united.ok) return KeepOutError{origin + ": the lines and areas do not unite into valid areas: " + united.error};
  out.obstacles = std::move(united.polygons);
  return out;
}

mapping::TypedOpResult without_keep_out(const mapping::TypedMultiPolygon& map,
                                        const mapping::TypedMultiPolygon& keep_out) {
  if (keep_out.empty() || map.empty()) {
    mapping::TypedOpResult same;
    same.ok = true;
    same.polygons = map;
    return same;
  }
  mapping::TypedOpOptions options;
  options.validate = false;
  return mapping::typed_difference(map, keep_out, std::nullopt, mapping::EdgeType::kObstacle, options);
}

const mapping::TypedOpResult& KeepOutCache::without_keep_out(
    const std::shared_ptr<const mapping::TypedMultiPolygon>& map,
    const std::shared_ptr<const mapping::TypedMultiPolygon>& keep_out) {
  if (map && keep_out && map == map_ && keep_out == keep_out_) {
    ++hits_;
    return result_;
  }
  ++misses_;
  map_ = map;
  keep_out_ = keep_out;
  result_ = map && keep_out ? planning::without_keep_out(*map, *keep_out) : mapping::TypedOpResult{};
  if (!map || !keep_out) result_.error = "no map or no keep-out";
  return result_;
}

}  // namespace pex::planning
