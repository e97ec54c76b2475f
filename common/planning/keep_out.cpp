#include "planning/keep_out.hpp"

#include <cmath>
#include <exception>

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

constexpr double kMaxCoordinate = geometry::kMaxFileCoordinateM;
using geometry::leading_keyword;
using geometry::trim_blanks;

bool coordinates_ok(const auto& geometry) {
  bool ok = true;
  bg::for_each_point(geometry, [&](const Point& p) {
    ok = ok && std::isfinite(p.x()) && std::isfinite(p.y()) && std::abs(p.x()) <= kMaxCoordinate &&
         std::abs(p.y()) <= kMaxCoordinate;
  });
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

std::variant<KeepOut, KeepOutError> parse_keep_out(std::string_view text, const std::string& origin,
                                                   const geometry::Pose2& start_in_file, double line_width_m) {
  KeepOut out;
  const geometry::PoseTransform to_map(geometry::inverse(start_in_file));
  MultiPolygon shapes;
  auto unite = [&](const auto& shape) {
    MultiPolygon united;
    bg::union_(shapes, shape, united);
    shapes = std::move(united);
  };
  auto add = [&](Polygon p) {
    for (Point& q : p.outer()) q = to_map(q);
    for (auto& inner : p.inners())
      for (Point& q : inner) q = to_map(q);
    bg::correct(p);
    unite(p);
  };
  auto add_line = [&](const Linestring& drawn) {
    Linestring line;
    for (const Point& q : drawn)
      if (line.empty() || !bg::equals(line.back(), to_map(q))) line.push_back(to_map(q));
    if (line.size() < 2) return;
    unite(strip(line, line_width_m));
    out.lines += static_cast<int>(line.size()) - 1;
  };
  auto add_area = [&](const Polygon& polygon) -> std::string {
    auto closed = [](const auto& ring) { return ring.size() >= 4 && bg::equals(ring.front(), ring.back()); };
    if (!closed(polygon.outer())) return "POLYGON ring not closed (its last point must be its first, 4 points at least)";
    for (const auto& inner : polygon.inners())
      if (!closed(inner)) return "POLYGON hole not closed (its last point must be its first, 4 points at least)";
    Polygon p = polygon;
    bg::correct(p);
    if (!bg::is_valid(p)) return "POLYGON is not a valid area (a ring crossing itself?)";
    add(std::move(p));
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
        if (!coordinates_ok(g)) return fail("coordinate not finite or beyond 1e5 m");
        add_line(g);
      } else if (keyword == "MULTILINESTRING") {
        MultiLinestring g;
        bg::read_wkt(line, g);
        if (!coordinates_ok(g)) return fail("coordinate not finite or beyond 1e5 m");
        for (const auto& l : g) add_line(l);
      } else if (keyword == "POLYGON") {
        Polygon g;
        bg::read_wkt(line, g);
        if (!coordinates_ok(g)) return fail("coordinate not finite or beyond 1e5 m");
        error = add_area(g);
      } else if (keyword == "MULTIPOLYGON") {
        MultiPolygon g;
        bg::read_wkt(line, g);
        if (!coordinates_ok(g)) return fail("coordinate not finite or beyond 1e5 m");
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
  out.obstacles = mapping::with_uniform_type(shapes, mapping::EdgeType::kObstacle);
  return out;
}

mapping::TypedMultiPolygon without_keep_out(const mapping::TypedMultiPolygon& map,
                                            const mapping::TypedMultiPolygon& keep_out, bool* failed) {
  if (failed) *failed = false;
  if (keep_out.empty() || map.empty()) return map;
  // Unchecked as the live view's union (live_view.cpp): the result only
  // feeds the C-space's offset; a failed overlay leaves the map as it is.
  mapping::TypedOpOptions options;
  options.validate = false;
  const auto cut = mapping::typed_difference(map, keep_out, std::nullopt, mapping::EdgeType::kObstacle, options);
  if (!cut.ok) {
    if (failed) *failed = true;
    return map;
  }
  return cut.polygons;
}

}  // namespace pex::planning
