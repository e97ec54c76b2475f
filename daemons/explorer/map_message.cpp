#include "map_message.hpp"

#include <cmath>
#include <map>
#include <vector>

#include <pex/polygon_ring_t.hpp>

namespace pex::explorer {

namespace {

namespace bg = boost::geometry;
using mapping::EdgeType;

// Copies of the message's constants: lcm-gen declares them without a
// definition, so they must not be bound to references.
constexpr std::int8_t kWireObstacle = pex::polygon_ring_t::EDGE_OBSTACLE;
constexpr std::int8_t kWireFrontier = pex::polygon_ring_t::EDGE_FRONTIER;

struct RawRing {
  std::vector<mapping::Point> points;  // open
  std::vector<EdgeType> types;
};

// Signed area (positive: counter-clockwise).
double signed_area(const std::vector<mapping::Point>& pts) {
  double twice = 0.0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto& a = pts[i];
    const auto& b = pts[(i + 1) % pts.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * twice;
}

// Reverses the ring's direction; edge i (v_i -> v_i+1) becomes the edge
// between the same two vertices the other way round.
void reverse_ring(RawRing& ring) {
  const std::size_t n = ring.points.size();
  std::vector<mapping::Point> points(ring.points.rbegin(), ring.points.rend());
  std::vector<EdgeType> types(n);
  for (std::size_t j = 0; j < n; ++j) types[j] = ring.types[(2 * n - 2 - j) % n];
  ring.points = std::move(points);
  ring.types = std::move(types);
}

mapping::Ring closed(const RawRing& ring) {
  mapping::Ring out(ring.points.begin(), ring.points.end());
  out.push_back(ring.points.front());
  return out;
}

}  // namespace

DecodedMap decode_map(const pex::polygon_map_t& msg, const MapDecodeOptions& options) {
  DecodedMap out;
  if (msg.nrings < 0 || static_cast<std::size_t>(msg.nrings) != msg.rings.size()) {
    out.error = "nrings disagrees with the rings array";
    return out;
  }
  std::int64_t total = 0;
  for (const auto& r : msg.rings) {
    if (r.nvertices < 0 || static_cast<std::size_t>(r.nvertices) != r.x.size() || r.x.size() != r.y.size() ||
        r.x.size() != r.edge_type.size()) {
      out.error = "a ring's arrays disagree with its nvertices";
      return out;
    }
    total += r.nvertices;
  }
  if (total > options.max_vertices) {
    out.error = "map has " + std::to_string(total) + " vertices, more than the limit " +
                std::to_string(options.max_vertices);
    return out;
  }

  struct Group {
    std::vector<RawRing> outers, holes;
  };
  std::map<std::int32_t, std::size_t> index_of;  // polygon id -> group, in order of appearance
  std::vector<Group> groups;
  for (const auto& r : msg.rings) {
    RawRing ring;
    for (std::int32_t i = 0; i < r.nvertices; ++i) {
      const double x = r.x[static_cast<std::size_t>(i)], y = r.y[static_cast<std::size_t>(i)];
      const auto t = r.edge_type[static_cast<std::size_t>(i)];
      if (!std::isfinite(x) || !std::isfinite(y)) {
        out.error = "non-finite vertex coordinate";
        return out;
      }
      if (std::abs(x) > options.max_abs_coordinate_m || std::abs(y) > options.max_abs_coordinate_m) {
        out.error = "vertex (" + std::to_string(x) + ", " + std::to_string(y) + ") beyond " +
                    std::to_string(options.max_abs_coordinate_m) + " m";
        return out;
      }
      if (t != kWireObstacle && t != kWireFrontier) {
        out.error = "unknown edge type " + std::to_string(static_cast<int>(t));
        return out;
      }
      const mapping::Point p(x, y);
      const EdgeType type = t == kWireObstacle ? EdgeType::kObstacle : EdgeType::kFrontier;
      if (!ring.points.empty() && bg::equals(ring.points.back(), p)) {
        ring.types.back() = type;  // a repeated vertex: the edge leaving it is the real one
        continue;
      }
      ring.points.push_back(p);
      ring.types.push_back(type);
    }
    // A closing vertex equal to the first: its edge is zero length.
    if (ring.points.size() > 1 && bg::equals(ring.points.front(), ring.points.back())) {
      ring.points.pop_back();
      ring.types.pop_back();
    }
    if (ring.points.size() < 3) {
      ++out.rings_dropped;
      continue;
    }
    const double area = signed_area(ring.points);
    if ((!r.hole && area < 0.0) || (r.hole && area > 0.0)) {
      reverse_ring(ring);
      ++out.rings_reoriented;
    }
    auto [it, inserted] = index_of.emplace(r.polygon, groups.size());
    if (inserted) groups.emplace_back();
    (r.hole ? groups[it->second].holes : groups[it->second].outers).push_back(std::move(ring));
  }

  for (const auto& g : groups) {
    if (g.outers.size() != 1) {
      ++out.polygons_dropped;
      continue;
    }
    mapping::TypedPolygon polygon;
    polygon.geometry.outer() = closed(g.outers[0]);
    polygon.edge_types.push_back(g.outers[0].types);
    for (const auto& h : g.holes) {
      polygon.geometry.inners().push_back(closed(h));
      polygon.edge_types.push_back(h.types);
    }
    if (!mapping::is_valid_cheap_first(polygon)) {
      ++out.polygons_dropped;
      continue;
    }
    out.polygons.push_back(std::move(polygon));
  }
  if (out.polygons.empty() && !groups.empty()) {
    out.error = "no valid polygon in the map (" + std::to_string(out.polygons_dropped) + " dropped)";
    return out;
  }
  out.ok = true;
  return out;
}

pex::polygon_map_t encode_map(const mapping::TypedMultiPolygon& polygons, std::int64_t utime) {
  pex::polygon_map_t msg{};
  msg.utime = utime;
  msg.scan_utime = utime;
  msg.particle = -1;
  auto add = [&](const mapping::Ring& ring, const std::vector<EdgeType>& types, std::int32_t polygon, bool hole) {
    pex::polygon_ring_t r{};
    r.polygon = polygon;
    r.hole = hole;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
      r.x.push_back(ring[i].x());
      r.y.push_back(ring[i].y());
      r.edge_type.push_back(types[i] == EdgeType::kObstacle ? kWireObstacle
                                                            : kWireFrontier);
    }
    r.nvertices = static_cast<std::int32_t>(r.x.size());
    msg.vertex_count += r.nvertices;
    msg.rings.push_back(std::move(r));
  };
  for (std::size_t p = 0; p < polygons.size(); ++p) {
    const auto& poly = polygons[p];
    add(poly.geometry.outer(), poly.edge_types[0], static_cast<std::int32_t>(p), false);
    for (std::size_t k = 0; k < poly.geometry.inners().size(); ++k)
      add(poly.geometry.inners()[k], poly.edge_types[1 + k], static_cast<std::int32_t>(p), true);
  }
  msg.nrings = static_cast<std::int32_t>(msg.rings.size());
  msg.free_area_m2 = mapping::area(polygons);
  msg.obstacle_length_m = mapping::edge_length(polygons, EdgeType::kObstacle);
  msg.frontier_length_m = mapping::edge_length(polygons, EdgeType::kFrontier);
  return msg;
}

}  // namespace pex::explorer
