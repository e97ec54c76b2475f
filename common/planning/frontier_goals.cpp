#include "planning/frontier_goals.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

#include <boost/geometry/index/rtree.hpp>

#include "planning/cspace.hpp"

namespace pex::planning {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

namespace {

bool is_frontier(mapping::EdgeType type) { return type != mapping::EdgeType::kObstacle; }

// The chains of one ring, each with the area the ring encloses (enclosed_areas).
void add_ring_chains(const mapping::Ring& ring, const std::vector<mapping::EdgeType>& types, double enclosed_area_m2,
                     std::vector<FrontierChain>& chains) {
  const std::size_t n = ring.size() < 2 ? 0 : ring.size() - 1;  // edges
  if (n == 0 || types.size() != n) return;
  std::size_t start = n;  // first edge of a chain: a frontier edge after an obstacle edge
  for (std::size_t i = 0; i < n; ++i) {
    if (is_frontier(types[i]) && !is_frontier(types[(i + n - 1) % n])) {
      start = i;
      break;
    }
  }
  if (start == n) {
    bool any = false;
    for (auto t : types) any = any || is_frontier(t);
    if (!any) return;
    FrontierChain chain;  // the whole ring is frontier
    chain.closed = true;
    chain.points.assign(ring.begin(), ring.end());
    chain.length_m = polyline_length(chain.points);
    chain.enclosed_area_m2 = enclosed_area_m2;
    chains.push_back(std::move(chain));
    return;
  }
  // Walk once around the ring from `start`, cutting at obstacle edges.
  FrontierChain current;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (start + k) % n;
    if (is_frontier(types[i])) {
      if (current.points.empty()) current.points.push_back(ring[i]);
      current.points.push_back(ring[i + 1]);
    } else if (!current.points.empty()) {
      current.length_m = polyline_length(current.points);
      current.enclosed_area_m2 = enclosed_area_m2;
      chains.push_back(std::move(current));
      current = FrontierChain{};
    }
  }
  if (!current.points.empty()) {
    current.length_m = polyline_length(current.points);
    current.enclosed_area_m2 = enclosed_area_m2;
    chains.push_back(std::move(current));
  }
}

}  // namespace

std::vector<std::vector<double>> enclosed_areas(const TypedMultiPolygon& map, int* polygons_not_placed) {
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> areas(map.size());
  struct Hole {
    std::size_t polygon, index;
    mapping::Box box;
    double area_m2;
  };
  std::vector<Hole> holes;
  std::vector<mapping::Box> outer_boxes(map.size());
  for (std::size_t p = 0; p < map.size(); ++p) {
    const auto& g = map[p].geometry;
    areas[p].assign(1 + g.inners().size(), kUnbounded);
    outer_boxes[p] = bg::return_envelope<mapping::Box>(g.outer());
    for (std::size_t k = 0; k < g.inners().size(); ++k)
      holes.push_back({p, k, bg::return_envelope<mapping::Box>(g.inners()[k]), std::abs(bg::area(g.inners()[k]))});
  }
  // The innermost hole holding each polygon (the smallest of those holding
  // it). The holes whose boxes cover the polygon's come from an rtree: a
  // map of many polygons and holes (a hostile MAP within max_map_vertices)
  // must not cost their product.
  std::vector<std::pair<mapping::Box, std::size_t>> boxes;
  boxes.reserve(holes.size());
  for (std::size_t h = 0; h < holes.size(); ++h) boxes.emplace_back(holes[h].box, h);
  const bgi::rtree<std::pair<mapping::Box, std::size_t>, bgi::rstar<16>> hole_index(boxes);
  // The tests read the hole's whole ring; a MAP of many polygons inside one
  // long hole (hostile: a building's map has few polygons in its holes)
  // would cost polygons x hole vertices. Past a budget of ring vertices
  // read, linear in the map's size, a polygon is left unplaced: it is
  // taken from no hole's region, and the holes it might lie in, and its own
  // outer ring, count as unbounded (their frontiers goals as any other),
  // so the budget can cost goals to visit, never a frontier skipped.
  std::size_t map_vertices = 0;
  for (const auto& polygon : map) {
    map_vertices += polygon.geometry.outer().size();
    for (const auto& inner : polygon.geometry.inners()) map_vertices += inner.size();
  }
  const std::size_t budget = kEnclosedLookupVerticesPerMapVertex * map_vertices + kEnclosedLookupVerticesFloor;
  std::size_t read = 0;
  std::vector<char> hole_unbounded(holes.size(), 0), placed(map.size(), 1);
  std::vector<int> holder(map.size(), -1);
  std::vector<std::pair<mapping::Box, std::size_t>> covering;
  for (std::size_t p = 0; p < map.size(); ++p) {
    const auto& outer = map[p].geometry.outer();
    if (outer.size() < 4) continue;
    covering.clear();
    hole_index.query(bgi::covers(outer_boxes[p]), std::back_inserter(covering));
    for (const auto& [box, h] : covering) {
      if (holes[h].polygon == p) continue;
      const auto& hole_ring = map[holes[h].polygon].geometry.inners()[holes[h].index];
      read += 3 * hole_ring.size();
      if (read > budget) {
        placed[p] = 0;
        hole_unbounded[h] = 1;
        continue;
      }
      // Polygons may touch at a vertex, where the crossing test is
      // arbitrary: three vertices spread over the ring vote.
      const std::size_t n = outer.size() - 1;
      int inside = 0;
      for (std::size_t v : {std::size_t{0}, n / 3, (2 * n) / 3}) inside += mapping::inside_ring(outer[v], hole_ring);
      if (inside >= 2 && (holder[p] < 0 || holes[h].area_m2 < holes[static_cast<std::size_t>(holder[p])].area_m2))
        holder[p] = static_cast<int>(h);
    }
  }
  int not_placed = 0;
  for (std::size_t p = 0; p < map.size(); ++p) {
    if (placed[p]) continue;
    ++not_placed;
    holder[p] = -1;  // its outer ring: unbounded; subtracted from no hole
  }
  if (polygons_not_placed) *polygons_not_placed = not_placed;
  std::vector<double> region(holes.size());
  for (std::size_t h = 0; h < holes.size(); ++h) region[h] = hole_unbounded[h] ? kUnbounded : holes[h].area_m2;
  for (std::size_t p = 0; p < map.size(); ++p)
    if (holder[p] >= 0) region[static_cast<std::size_t>(holder[p])] -= std::abs(bg::area(map[p].geometry.outer()));
  for (std::size_t h = 0; h < holes.size(); ++h)
    areas[holes[h].polygon][1 + holes[h].index] = std::max(0.0, region[h]);
  for (std::size_t p = 0; p < map.size(); ++p)
    if (holder[p] >= 0) areas[p][0] = std::max(0.0, region[static_cast<std::size_t>(holder[p])]);
  return areas;
}

std::vector<FrontierChain> frontier_chains(const TypedMultiPolygon& map, int* polygons_not_placed) {
  std::vector<FrontierChain> chains;
  const auto areas = enclosed_areas(map, polygons_not_placed);
  for (std::size_t p = 0; p < map.size(); ++p) {
    const auto& polygon = map[p];
    if (!mapping::types_match_rings(polygon)) continue;
    add_ring_chains(polygon.geometry.outer(), polygon.edge_types[0], areas[p][0], chains);
    for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
      add_ring_chains(polygon.geometry.inners()[k], polygon.edge_types[1 + k], areas[p][1 + k], chains);
  }
  return chains;
}

Point point_at_arc_length(const std::vector<Point>& polyline, double s) {
  if (polyline.empty()) return Point(0.0, 0.0);
  for (std::size_t i = 1; i < polyline.size(); ++i) {
    const double len = distance(polyline[i - 1], polyline[i]);
    if (s <= len && len > 0.0) {
      const double t = std::max(0.0, s / len);
      return Point(polyline[i - 1].x() + t * (polyline[i].x() - polyline[i - 1].x()),
                   polyline[i - 1].y() + t * (polyline[i].y() - polyline[i - 1].y()));
    }
    s -= len;
  }
  return polyline.back();
}

std::vector<FrontierPoint> frontier_candidates(const std::vector<FrontierChain>& chains,
                                               const FrontierGoalOptions& options, int* dropped_chains) {
  std::vector<FrontierPoint> out;
  int dropped = 0;
  const double span = 2.0 * options.sensor_range_m;
  for (std::size_t c = 0; c < chains.size(); ++c) {
    const auto& chain = chains[c];
    if (!(chain.length_m >= options.min_frontier_length_m) || !(span > 0.0)) {
      ++dropped;
      continue;
    }
    const int n = std::max(1, static_cast<int>(std::ceil(chain.length_m / span)));
    const double piece = chain.length_m / n;
    for (int i = 0; i < n; ++i)
      out.push_back(FrontierPoint{point_at_arc_length(chain.points, (i + 0.5) * piece), static_cast<int>(c),
                                  chain.length_m, i * piece, (i + 1) * piece});
  }
  if (dropped_chains) *dropped_chains = dropped;
  return out;
}

}  // namespace pex::planning
