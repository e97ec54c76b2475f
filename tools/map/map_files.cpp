#include "map_files.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include <nlohmann/json.hpp>

#include "mapping/typed_polygon.hpp"

namespace pex::map_files {

namespace {

using nlohmann::json;

constexpr int kFormatVersion = 1;

const char* type_name(std::int8_t t) { return t == pex::polygon_ring_t::EDGE_FRONTIER ? "frontier" : "obstacle"; }

[[noreturn]] void fail(const std::string& where, const std::string& why) {
  throw MapFileError(where.empty() ? why : where + ": " + why);
}

// A member of `j` as T, or a MapFileError naming it.
template <class T>
T member(const json& j, const char* key, const std::string& where) {
  if (!j.is_object() || !j.contains(key)) fail(where, std::string("no \"") + key + "\"");
  try {
    return j.at(key).get<T>();
  } catch (const json::exception&) {
    fail(where, std::string("\"") + key + "\" has the wrong type");
  }
}

}  // namespace

std::string check_map(const pex::polygon_map_t& map) {
  if (map.nrings < 0 || static_cast<std::size_t>(map.nrings) != map.rings.size())
    return "nrings " + std::to_string(map.nrings) + " but " + std::to_string(map.rings.size()) + " rings";
  std::map<int, std::size_t> last_ring_of;  // polygon -> its last ring so far
  for (std::size_t r = 0; r < map.rings.size(); ++r) {
    const auto& ring = map.rings[r];
    const std::string where = "ring " + std::to_string(r) + ": ";
    const auto n = static_cast<std::size_t>(std::max(ring.nvertices, 0));
    if (ring.nvertices < 3 || ring.x.size() != n || ring.y.size() != n || ring.edge_type.size() != n)
      return where + "nvertices " + std::to_string(ring.nvertices) + " disagrees with its arrays or is below 3";
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(ring.x[i]) || !std::isfinite(ring.y[i])) return where + "non-finite vertex";
      if (ring.edge_type[i] != pex::polygon_ring_t::EDGE_OBSTACLE &&
          ring.edge_type[i] != pex::polygon_ring_t::EDGE_FRONTIER)
        return where + "unknown edge type " + std::to_string(ring.edge_type[i]);
    }
    const auto seen = last_ring_of.find(ring.polygon);
    if (!ring.hole && seen != last_ring_of.end()) return where + "a second outer ring of polygon " + std::to_string(ring.polygon);
    if (ring.hole && (seen == last_ring_of.end() || seen->second != r - 1))
      return where + "a hole not right after its polygon's outer ring or holes";
    last_ring_of[ring.polygon] = r;
  }
  return {};
}

std::string geometry_problem(const pex::polygon_map_t& map) {
  if (auto why = check_map(map); !why.empty()) return why;
  mapping::TypedMultiPolygon polygons;
  for (std::size_t r = 0; r < map.rings.size(); ++r) {
    const auto& ring = map.rings[r];
    if (!ring.hole) polygons.emplace_back();  // check_map: a hole follows its outer ring
    mapping::Ring points;
    for (std::size_t i = 0; i < ring.x.size(); ++i) points.emplace_back(ring.x[i], ring.y[i]);
    points.push_back(points.front());
    std::vector<mapping::EdgeType> types;
    for (const auto t : ring.edge_type)
      types.push_back(t == pex::polygon_ring_t::EDGE_OBSTACLE ? mapping::EdgeType::kObstacle
                                                              : mapping::EdgeType::kFrontier);
    auto& polygon = polygons.back();
    (ring.hole ? polygon.geometry.inners().emplace_back() : polygon.geometry.outer()) = std::move(points);
    polygon.edge_types.push_back(std::move(types));
  }
  std::string why;
  if (mapping::is_valid(polygons, &why)) return {};
  return why.empty() ? "not a valid multi-polygon" : why;
}

std::string to_geojson(const pex::polygon_map_t& map) {
  if (auto why = check_map(map); !why.empty()) throw MapFileError("map cannot be written: " + why);
  json features = json::array();
  for (std::size_t r = 0; r < map.rings.size();) {
    const int polygon = map.rings[r].polygon;
    json coordinates = json::array(), edge_types = json::array();
    for (; r < map.rings.size() && map.rings[r].polygon == polygon && (coordinates.empty() || map.rings[r].hole); ++r) {
      const auto& ring = map.rings[r];
      json points = json::array(), types = json::array();
      for (std::size_t i = 0; i < ring.x.size(); ++i) {
        points.push_back({ring.x[i], ring.y[i]});
        types.push_back(type_name(ring.edge_type[i]));
      }
      points.push_back({ring.x[0], ring.y[0]});  // GeoJSON rings are closed
      coordinates.push_back(std::move(points));
      edge_types.push_back(std::move(types));
    }
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "Polygon"}, {"coordinates", std::move(coordinates)}}},
                        {"properties",
                         {{"polygon", polygon},
                          {"edge_types", std::move(edge_types)},
                          {"frame", "map"},
                          {"utime", map.utime}}}});
  }
  json out = {{"type", "FeatureCollection"},
              {"pex_map_format", kFormatVersion},
              {"frame", "map"},
              {"units", "m"},
              {"utime", map.utime},
              {"scan_utime", map.scan_utime},
              {"particle", map.particle},
              {"generation", map.generation},
              {"scans_inserted", map.scans_inserted},
              {"vertex_count", map.vertex_count},
              {"free_area_m2", map.free_area_m2},
              {"obstacle_length_m", map.obstacle_length_m},
              {"frontier_length_m", map.frontier_length_m},
              {"robot", {{"x", map.robot_x}, {"y", map.robot_y}, {"theta", map.robot_theta}}},
              {"features", std::move(features)}};
  return out.dump(1) + "\n";
}

pex::polygon_map_t from_geojson(std::string_view text) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    fail("", std::string("not JSON: ") + e.what());
  }
  if (member<std::string>(j, "type", "") != "FeatureCollection") fail("", "not a GeoJSON FeatureCollection");
  const int version = member<int>(j, "pex_map_format", "");
  if (version != kFormatVersion)
    fail("", "pex_map_format " + std::to_string(version) + ", this program reads " + std::to_string(kFormatVersion));
  if (member<std::string>(j, "frame", "") != "map") fail("", "frame is not \"map\"");
  pex::polygon_map_t m{};
  m.utime = member<std::int64_t>(j, "utime", "");
  m.scan_utime = member<std::int64_t>(j, "scan_utime", "");
  m.particle = member<std::int32_t>(j, "particle", "");
  m.generation = member<std::int64_t>(j, "generation", "");
  m.scans_inserted = member<std::int32_t>(j, "scans_inserted", "");
  m.vertex_count = member<std::int32_t>(j, "vertex_count", "");
  m.free_area_m2 = member<double>(j, "free_area_m2", "");
  m.obstacle_length_m = member<double>(j, "obstacle_length_m", "");
  m.frontier_length_m = member<double>(j, "frontier_length_m", "");
  const json robot = member<json>(j, "robot", "");
  m.robot_x = member<double>(robot, "x", "robot");
  m.robot_y = member<double>(robot, "y", "robot");
  m.robot_theta = member<double>(robot, "theta", "robot");
  const json features = member<json>(j, "features", "");
  if (!features.is_array()) fail("", "\"features\" is not an array");
  for (std::size_t f = 0; f < features.size(); ++f) {
    const std::string where = "features[" + std::to_string(f) + "]";
    const json& feature = features[f];
    const json geometry = member<json>(feature, "geometry", where);
    if (member<std::string>(geometry, "type", where + ".geometry") != "Polygon") fail(where, "geometry is not a Polygon");
    const json coordinates = member<json>(geometry, "coordinates", where + ".geometry");
    const json properties = member<json>(feature, "properties", where);
    const int polygon = member<int>(properties, "polygon", where + ".properties");
    const json edge_types = member<json>(properties, "edge_types", where + ".properties");
    if (!coordinates.is_array() || coordinates.empty() || !edge_types.is_array() ||
        edge_types.size() != coordinates.size())
      fail(where, "coordinates and edge_types must be arrays of the same number of rings, at least one");
    for (std::size_t r = 0; r < coordinates.size(); ++r) {
      const std::string ring_where = where + " ring " + std::to_string(r);
      const json& points = coordinates[r];
      const json& types = edge_types[r];
      if (!points.is_array() || points.size() < 4) fail(ring_where, "fewer than 3 distinct points");
      if (!types.is_array() || types.size() + 1 != points.size())
        fail(ring_where, "edge_types has " + std::to_string(types.size()) + " entries for " +
                             std::to_string(points.size() - 1) + " edges");
      pex::polygon_ring_t ring{};
      ring.polygon = polygon;
      ring.hole = r > 0;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const json& p = points[i];
        if (!p.is_array() || p.size() < 2 || !p[0].is_number() || !p[1].is_number())
          fail(ring_where, "point " + std::to_string(i) + " is not [x, y]");
        const double x = p[0].get<double>(), y = p[1].get<double>();
        if (!std::isfinite(x) || !std::isfinite(y)) fail(ring_where, "non-finite point");
        if (i + 1 == points.size()) {
          if (x != ring.x[0] || y != ring.y[0]) fail(ring_where, "not closed (last point is not the first)");
          break;
        }
        ring.x.push_back(x);
        ring.y.push_back(y);
        const std::string type = types[i].is_string() ? types[i].get<std::string>() : "";
        if (type == "obstacle")
          ring.edge_type.push_back(std::int8_t{pex::polygon_ring_t::EDGE_OBSTACLE});
        else if (type == "frontier")
          ring.edge_type.push_back(std::int8_t{pex::polygon_ring_t::EDGE_FRONTIER});
        else
          fail(ring_where, "edge " + std::to_string(i) + ": type is not \"obstacle\" or \"frontier\"");
      }
      ring.nvertices = static_cast<std::int32_t>(ring.x.size());
      m.rings.push_back(std::move(ring));
    }
  }
  m.nrings = static_cast<std::int32_t>(m.rings.size());
  if (auto why = check_map(m); !why.empty()) fail("", why);
  return m;
}

OccupancyGrid rasterise(const pex::polygon_map_t& map, double resolution_m, double margin_m, std::int64_t max_cells) {
  if (auto why = check_map(map); !why.empty()) throw MapFileError("map cannot be rasterised: " + why);
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m)) throw MapFileError("resolution must be above 0");
  if (!(margin_m >= 0.0) || !std::isfinite(margin_m)) throw MapFileError("margin must not be negative");
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
  for (const auto& ring : map.rings)
    for (std::size_t i = 0; i < ring.x.size(); ++i) {
      lo_x = std::min(lo_x, ring.x[i]), hi_x = std::max(hi_x, ring.x[i]);
      lo_y = std::min(lo_y, ring.y[i]), hi_y = std::max(hi_y, ring.y[i]);
    }
  if (map.rings.empty()) lo_x = lo_y = hi_x = hi_y = 0.0;
  OccupancyGrid g;
  g.resolution_m = resolution_m;
  g.origin_x_m = lo_x - margin_m;
  g.origin_y_m = lo_y - margin_m;
  const double w = std::ceil((hi_x - lo_x + 2 * margin_m) / resolution_m);
  const double h = std::ceil((hi_y - lo_y + 2 * margin_m) / resolution_m);
  if (w * h > static_cast<double>(max_cells))
    throw MapFileError("a grid of " + std::to_string(w) + " x " + std::to_string(h) + " cells is more than " +
                       std::to_string(max_cells) + ": choose a coarser resolution");
  g.width = std::max(1, static_cast<int>(w));
  g.height = std::max(1, static_cast<int>(h));
  g.cells.assign(static_cast<std::size_t>(g.width) * g.height, OccupancyGrid::kUnknown);

  // Free: scanline at each row's centre, even-odd over every ring.
  std::vector<double> xs;
  for (int row = 0; row < g.height; ++row) {
    const double y = g.y_of(row);
    xs.clear();
    for (const auto& ring : map.rings) {
      const std::size_t n = ring.x.size();
      for (std::size_t i = 0; i < n; ++i) {
        const double x0 = ring.x[i], y0 = ring.y[i], x1 = ring.x[(i + 1) % n], y1 = ring.y[(i + 1) % n];
        if ((y0 <= y) != (y1 <= y)) xs.push_back(x0 + (y - y0) / (y1 - y0) * (x1 - x0));
      }
    }
    std::sort(xs.begin(), xs.end());
    for (std::size_t k = 0; k + 1 < xs.size(); k += 2) {
      // Cells whose centre x is in [xs[k], xs[k + 1]).
      const int first = std::max(0, static_cast<int>(std::ceil((xs[k] - g.origin_x_m) / resolution_m - 0.5)));
      const int last = std::min(g.width - 1, static_cast<int>(std::ceil((xs[k + 1] - g.origin_x_m) / resolution_m - 0.5)) - 1);
      for (int col = first; col <= last; ++col) g.cells[static_cast<std::size_t>(row) * g.width + col] = OccupancyGrid::kFree;
    }
  }

  // Occupied: every cell an obstacle edge passes through (grid traversal, Amanatides & Woo 1987).
  const auto mark = [&g](long cx, long cy) {  // cy counts up from the bottom row
    if (cx < 0 || cy < 0 || cx >= g.width || cy >= g.height) return;
    g.cells[static_cast<std::size_t>(g.height - 1 - cy) * g.width + cx] = OccupancyGrid::kOccupied;
  };
  for (const auto& ring : map.rings) {
    const std::size_t n = ring.x.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (ring.edge_type[i] != pex::polygon_ring_t::EDGE_OBSTACLE) continue;
      const double fx0 = (ring.x[i] - g.origin_x_m) / resolution_m, fy0 = (ring.y[i] - g.origin_y_m) / resolution_m;
      const double fx1 = (ring.x[(i + 1) % n] - g.origin_x_m) / resolution_m;
      const double fy1 = (ring.y[(i + 1) % n] - g.origin_y_m) / resolution_m;
      long cx = static_cast<long>(std::floor(fx0)), cy = static_cast<long>(std::floor(fy0));
      const long ex = static_cast<long>(std::floor(fx1)), ey = static_cast<long>(std::floor(fy1));
      const double dx = fx1 - fx0, dy = fy1 - fy0;
      const long sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1;
      const double inf = std::numeric_limits<double>::infinity();
      double t_x = dx == 0 ? inf : (sx > 0 ? cx + 1 - fx0 : fx0 - cx) / std::abs(dx);
      double t_y = dy == 0 ? inf : (sy > 0 ? cy + 1 - fy0 : fy0 - cy) / std::abs(dy);
      const double step_x = dx == 0 ? inf : 1.0 / std::abs(dx), step_y = dy == 0 ? inf : 1.0 / std::abs(dy);
      mark(cx, cy);
      for (long steps = std::abs(ex - cx) + std::abs(ey - cy); steps > 0; --steps) {
        if (t_x < t_y) {
          cx += sx;
          t_x += step_x;
        } else {
          cy += sy;
          t_y += step_y;
        }
        mark(cx, cy);
      }
    }
  }
  return g;
}

std::string to_pgm(const OccupancyGrid& grid) {
  std::string out = "P5\n# polyexplore map, " + std::to_string(grid.resolution_m) + " m/cell\n" +
                    std::to_string(grid.width) + " " + std::to_string(grid.height) + "\n255\n";
  out.append(reinterpret_cast<const char*>(grid.cells.data()), grid.cells.size());
  return out;
}

std::string to_yaml(const OccupancyGrid& grid, const std::string& image_file) {
  char numbers[160];
  std::snprintf(numbers, sizeof numbers, "resolution: %.17g\norigin: [%.17g, %.17g, 0.0]\n", grid.resolution_m,
                grid.origin_x_m, grid.origin_y_m);
  // map_server: p = (255 - value) / 255 with negate 0: 0 -> 1.0 occupied,
  // 254 -> 0.004 free, 205 -> 0.196 just above free_thresh: unknown.
  return "image: " + image_file + "\n" + numbers +
         "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";
}

OccupancyGrid from_pgm(std::string_view bytes) {
  std::size_t pos = 0;
  // The next header token, skipping white space and comments.
  const auto token = [&]() -> std::string {
    while (pos < bytes.size()) {
      if (bytes[pos] == '#') {
        while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
      } else if (std::isspace(static_cast<unsigned char>(bytes[pos]))) {
        ++pos;
      } else {
        break;
      }
    }
    const std::size_t start = pos;
    while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    return std::string(bytes.substr(start, pos - start));
  };
  if (token() != "P5") throw MapFileError("not a binary PGM (P5)");
  OccupancyGrid g;
  try {
    g.width = std::stoi(token());
    g.height = std::stoi(token());
    if (std::stoi(token()) != 255) throw MapFileError("PGM maxval is not 255");
  } catch (const std::logic_error&) {
    throw MapFileError("PGM header is not width, height and maxval");
  }
  ++pos;  // the one white space character after maxval
  const auto size = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  if (g.width <= 0 || g.height <= 0 || pos > bytes.size() || bytes.size() - pos != size)
    throw MapFileError("PGM holds " + std::to_string(bytes.size() - std::min(pos, bytes.size())) + " bytes of pixels, " +
                       std::to_string(g.width) + " x " + std::to_string(g.height) + " expected");
  g.cells.assign(bytes.begin() + static_cast<std::ptrdiff_t>(pos), bytes.end());
  return g;
}

}  // namespace pex::map_files
