#include "planning/frontier_goals.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <optional>
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
                     int polygon, int ring_index, std::vector<FrontierChain>& chains) {
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
    chain.polygon = polygon;
    chain.ring = ring_index;
    chain.first_edge = 0;
    chain.edge_count = n;
    chains.push_back(std::move(chain));
    return;
  }
  // Walk once around the ring from `start`, cutting at obstacle edges.
  FrontierChain current;
  auto finish = [&] {
    current.length_m = polyline_length(current.points);
    current.enclosed_area_m2 = enclosed_area_m2;
    current.polygon = polygon;
    current.ring = ring_index;
    current.edge_count = current.points.size() - 1;
    chains.push_back(std::move(current));
    current = FrontierChain{};
  };
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (start + k) % n;
    if (is_frontier(types[i])) {
      if (current.points.empty()) {
        current.points.push_back(ring[i]);
        current.first_edge = i;
      }
      current.points.push_back(ring[i + 1]);
    } else if (!current.points.empty()) {
      finish();
    }
  }
  if (!current.points.empty()) finish();
}

double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// The points of every ring of the map (closing points counted): what the
// work budgets of enclosed_areas and find_walled_bays scale with.
std::size_t ring_points(const TypedMultiPolygon& map) {
  std::size_t points = 0;
  for (const auto& polygon : map) {
    points += polygon.geometry.outer().size();
    for (const auto& inner : polygon.geometry.inners()) points += inner.size();
  }
  return points;
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
  const std::size_t map_vertices = ring_points(map);
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
    add_ring_chains(polygon.geometry.outer(), polygon.edge_types[0], areas[p][0], static_cast<int>(p), 0, chains);
    for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
      add_ring_chains(polygon.geometry.inners()[k], polygon.edge_types[1 + k], areas[p][1 + k], static_cast<int>(p),
                      static_cast<int>(1 + k), chains);
  }
  return chains;
}

void find_walled_bays(const TypedMultiPolygon& map, std::vector<FrontierChain>& chains,
                      const WalledBayOptions& options) {
  if (!(options.max_area_m2 > 0.0) || !(options.max_lid_m > 0.0)) return;
  // Every edge of the map, frontier or obstacle: a lid may cross none but
  // its own loop's (below). Built when a first lid gets that far.
  struct EdgeRef {
    std::size_t polygon, ring, edge;
    bool operator==(const EdgeRef&) const = default;
  };
  using Value = std::pair<mapping::Segment, EdgeRef>;
  std::optional<bgi::rtree<Value, bgi::rstar<16>>> edges;
  // The lid u -> w, short of each end, where it meets the walls it
  // continues: the ragged steps of a wall's obstacle band, where the wall
  // meets a frontier, cross the wall's line by centimetres. Edges `in_loop`
  // accepts are not counted: the loop's own edges cross the lid only within
  // max_beyond_lid_m of its line (checked before), the band's steps again.
  auto lid_crosses_an_edge = [&](const Point& u, const Point& w, auto in_loop) {
    if (!edges) {
      std::vector<Value> values;
      for (std::size_t p = 0; p < map.size(); ++p) {
        const auto& piece = map[p];
        if (std::abs(bg::area(piece.geometry.outer())) < options.min_piece_m2) continue;
        auto add_ring = [&](const mapping::Ring& ring, std::size_t r) {
          for (std::size_t i = 0; i + 1 < ring.size(); ++i)
            values.emplace_back(mapping::Segment(ring[i], ring[i + 1]), EdgeRef{p, r, i});
        };
        add_ring(piece.geometry.outer(), 0);
        for (std::size_t k = 0; k < piece.geometry.inners().size(); ++k) add_ring(piece.geometry.inners()[k], 1 + k);
      }
      edges.emplace(values.begin(), values.end());
    }
    auto short_of = [&](const Point& from, const Point& to) {  // `from` moved towards `to`
      const double d = distance(from, to), t = std::min(options.lid_end_tolerance_m, 0.25 * d) / d;
      return Point(from.x() + t * (to.x() - from.x()), from.y() + t * (to.y() - from.y()));
    };
    const Point a = short_of(u, w), b = short_of(w, u);
    for (auto it = edges->qbegin(bgi::intersects(mapping::Segment(a, b))); it != edges->qend(); ++it)
      if (!in_loop(it->second) && segments_intersect(a, b, it->first.first, it->first.second)) return true;
    return false;
  };
  const double cos_turn = std::cos(options.max_lid_turn_rad);
  // A right angle give or take max_corner_turn_rad: its sine is at least this.
  const double cos_corner = std::cos(options.max_corner_turn_rad);
  // A budget of ring steps for the walks and the face tests, linear in the
  // map's size: a hostile map of many tiny edges must not cost chains x
  // pairs x ring. Past it no more bays are looked for, which leaves their
  // frontiers goals, as without the rule.
  const std::size_t map_vertices = ring_points(map);
  std::int64_t steps_left = static_cast<std::int64_t>(kWalledBayStepsPerMapVertex * map_vertices + kWalledBayStepsFloor);
  for (FrontierChain& chain : chains) {
    if (steps_left <= 0) break;
    if (chain.closed || chain.polygon < 0 || static_cast<std::size_t>(chain.polygon) >= map.size()) continue;
    const auto& polygon = map[static_cast<std::size_t>(chain.polygon)];
    const auto& ring = chain.ring == 0 ? polygon.geometry.outer()
                                       : polygon.geometry.inners()[static_cast<std::size_t>(chain.ring - 1)];
    const auto& types = polygon.edge_types[static_cast<std::size_t>(chain.ring)];
    const std::size_t n = ring.size() - 1;
    if (chain.edge_count >= n) continue;
    auto edge_length = [&](std::size_t i) { return distance(ring[i], ring[i + 1]); };
    auto is_wall = [&](std::size_t i) {
      return types[i] == mapping::EdgeType::kObstacle && edge_length(i) >= options.min_wall_m;
    };
    // Wall edges before the chain (each with the steps back from the chain's
    // first edge) and after it, within search_m along the ring; the two
    // walks share no edge.
    const std::size_t free_edges = n - chain.edge_count;
    std::vector<std::size_t> before, after;  // steps: 1 = the edge next to the chain
    double walked = 0.0;
    std::size_t back = 0;
    while (back < free_edges && walked < options.search_m && steps_left-- > 0) {
      ++back;
      const std::size_t i = (chain.first_edge + n - back) % n;
      if (is_wall(i)) before.push_back(back);
      walked += edge_length(i);
    }
    walked = 0.0;
    for (std::size_t ahead = 1; ahead + back <= free_edges && walked < options.search_m && steps_left-- > 0; ++ahead) {
      const std::size_t i = (chain.first_edge + chain.edge_count - 1 + ahead) % n;
      if (is_wall(i)) after.push_back(ahead);
      walked += edge_length(i);
    }
    if (before.empty() || after.empty()) continue;
    // The loop from u (the end of a wall edge before the chain) along the
    // ring to w (the start of one after it), closed by the lid w -> u. The
    // ring has the free space on its left, so a loop round unknown space
    // turns clockwise: its signed area is negative.
    const Point origin = ring[chain.first_edge];
    auto ring_index = [&](std::ptrdiff_t k) {  // of the vertex (and edge) k steps from the chain's first
      const auto signed_n = static_cast<std::ptrdiff_t>(n);
      return static_cast<std::size_t>(((static_cast<std::ptrdiff_t>(chain.first_edge) + k) % signed_n + signed_n) %
                                      signed_n);
    };
    auto vertex = [&](std::ptrdiff_t k) { return ring[ring_index(k)]; };
    const std::ptrdiff_t first = -static_cast<std::ptrdiff_t>(back) + 1;
    const std::ptrdiff_t last = static_cast<std::ptrdiff_t>(chain.edge_count + after.back()) - 1;
    // Twice the signed area swept from `origin` by the ring's edges, summed
    // from vertex `first` on: the loop's area in O(1) per pair.
    auto rel_cross = [&](const Point& p, const Point& q) {
      return cross(p.x() - origin.x(), p.y() - origin.y(), q.x() - origin.x(), q.y() - origin.y());
    };
    std::vector<double> swept(static_cast<std::size_t>(last - first + 1), 0.0);
    for (std::ptrdiff_t k = first; k < last; ++k)
      swept[static_cast<std::size_t>(k - first + 1)] = swept[static_cast<std::size_t>(k - first)] +
                                                        rel_cross(vertex(k), vertex(k + 1));
    double best = std::numeric_limits<double>::infinity();
    for (const std::size_t b_steps : before) {
      const std::ptrdiff_t ku = -static_cast<std::ptrdiff_t>(b_steps) + 1;  // u: the end of that wall edge
      const Point u = vertex(ku), u_from = vertex(ku - 1);
      const double bx = (u.x() - u_from.x()) / distance(u_from, u), by = (u.y() - u_from.y()) / distance(u_from, u);
      for (const std::size_t a_steps : after) {
        const std::ptrdiff_t kw = static_cast<std::ptrdiff_t>(chain.edge_count + a_steps) - 1;  // w: its start
        const Point w = vertex(kw), w_to = vertex(kw + 1);
        const double ax = (w_to.x() - w.x()) / distance(w, w_to), ay = (w_to.y() - w.y()) / distance(w, w_to);
        // The lid: straight on from u to w, the two walls in line with it;
        // or, in a room's corner, in line with one of them, the other wall
        // meeting the lid's line where the lid ends and turning off it into
        // the room (left, the free side) at about a right angle: the desk in
        // the corner hides the far wall up to the side wall. (Never round a
        // corner: the wall before u and one seen through a door beyond would
        // close a room's worth of unknown as readily as the corner behind a
        // desk.)
        const double lid = distance(u, w);
        if (!(lid >= 0.01) || lid > options.max_lid_m) continue;
        const double lx = (w.x() - u.x()) / lid, ly = (w.y() - u.y()) / lid;
        const bool before_in_line = lx * bx + ly * by >= cos_turn, after_in_line = lx * ax + ly * ay >= cos_turn;
        // The corner: the side wall's end off the line of the wall the lid
        // continues (u_from -> u, or w -> w_to) by at most max_beyond_lid_m,
        // and the side wall turning left from the lid (or the lid from it).
        auto off_line = [](const Point& p, const Point& on, double dx, double dy) {
          return std::abs((p.x() - on.x()) * dy - (p.y() - on.y()) * dx);
        };
        const bool corner_at_w = before_in_line && off_line(w, u, bx, by) <= options.max_beyond_lid_m &&
                                 cross(lx, ly, ax, ay) >= cos_corner;
        const bool corner_at_u = after_in_line && off_line(u, w, ax, ay) <= options.max_beyond_lid_m &&
                                 cross(bx, by, lx, ly) >= cos_corner;
        if (!(before_in_line && after_in_line) && !corner_at_w && !corner_at_u) continue;
        const double twice_area = swept[static_cast<std::size_t>(kw - first)] -
                                  swept[static_cast<std::size_t>(ku - first)] + rel_cross(w, u);
        const double area = -0.5 * twice_area;  // > 0 round unknown space
        if (!(area > 0.0) || area >= options.max_area_m2 || area >= best) continue;
        // The object in front of the lid: a wall edge of the loop (not the
        // two the lid continues) whose middle is min_depth_m from the lid.
        bool faced = false;
        for (std::ptrdiff_t k = ku; k < kw && !faced && steps_left > 0; ++k, --steps_left) {
          const Point a = vertex(k), b = vertex(k + 1);
          const Point middle(0.5 * (a.x() + b.x()), 0.5 * (a.y() + b.y()));
          faced = is_wall(ring_index(k)) && distance(middle, closest_point_on_segment(middle, u, w)) >= options.min_depth_m;
        }
        if (!faced) continue;
        // The loop stays on the bay's side of the lid (its left, u -> w),
        // but for the band's steps: a loop that goes further beyond the lid
        // round free space (a door the laser saw through, a room seen past
        // the object) closes no bay.
        bool beyond = false;
        std::ptrdiff_t k = ku + 1;
        for (; k < kw && !beyond && steps_left > 0; ++k, --steps_left) {
          const Point p = vertex(k);
          beyond = (p.x() - u.x()) * ly - (p.y() - u.y()) * lx > options.max_beyond_lid_m;
        }
        if (!beyond && k < kw) continue;  // the budget ran out before the loop was read: no bay
        const std::size_t loop_start = ring_index(ku);
        const auto loop_edges = static_cast<std::size_t>(kw - ku);
        auto in_loop = [&](const EdgeRef& e) {
          return e.polygon == static_cast<std::size_t>(chain.polygon) &&
                 e.ring == static_cast<std::size_t>(chain.ring) && (e.edge + n - loop_start) % n < loop_edges;
        };
        if (beyond || lid_crosses_an_edge(u, w, in_loop)) continue;
        best = area;
      }
    }
    chain.bay_area_m2 = best;
  }
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
