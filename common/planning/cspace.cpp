#include "planning/cspace.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/function_output_iterator.hpp>

#include "mapping/typed_ops.hpp"

namespace pex::planning {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

// Not std::hypot: it guards against overflow that map coordinates (checked
// finite, far below 1e150) cannot reach, and it was 8 % of a plan's CPU time
// (perf over `pex-plan --every-map` on a campus mission log).
double distance(const Point& a, const Point& b) {
  const double dx = a.x() - b.x(), dy = a.y() - b.y();
  return std::sqrt(dx * dx + dy * dy);
}

Point closest_point_on_segment(const Point& p, const Point& a, const Point& b) {
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  const double len2 = dx * dx + dy * dy;
  if (len2 <= 0.0) return a;
  double t = ((p.x() - a.x()) * dx + (p.y() - a.y()) * dy) / len2;
  t = std::clamp(t, 0.0, 1.0);
  return Point(a.x() + t * dx, a.y() + t * dy);
}

namespace {

double orient(const Point& p, const Point& q, const Point& r) {
  return (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
}

// r is collinear with p-q: is it within the segment's box?
bool within_box(const Point& p, const Point& q, const Point& r) {
  return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
         std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
}

double segment_distance(const Point& p, const Point& a, const Point& b) {
  return distance(p, closest_point_on_segment(p, a, b));
}

mapping::Box box_of(const Point& a, const Point& b) {
  return mapping::Box(Point(std::min(a.x(), b.x()), std::min(a.y(), b.y())),
                      Point(std::max(a.x(), b.x()), std::max(a.y(), b.y())));
}

}  // namespace

bool segments_intersect(const Point& p1, const Point& p2, const Point& q1, const Point& q2) {
  const double d1 = orient(q1, q2, p1), d2 = orient(q1, q2, p2);
  const double d3 = orient(p1, p2, q1), d4 = orient(p1, p2, q2);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return true;
  if (d1 == 0 && within_box(q1, q2, p1)) return true;
  if (d2 == 0 && within_box(q1, q2, p2)) return true;
  if (d3 == 0 && within_box(p1, p2, q1)) return true;
  if (d4 == 0 && within_box(p1, p2, q2)) return true;
  return false;
}

Point left_normal(const Point& a, const Point& b) {
  const double len = distance(a, b);
  if (len <= 0.0) return Point(0.0, 0.0);
  return Point(-(b.y() - a.y()) / len, (b.x() - a.x()) / len);
}

double segment_distance(const Point& p1, const Point& p2, const Point& q1, const Point& q2) {
  if (segments_intersect(p1, p2, q1, q2)) return 0.0;
  // Apart, the nearest points of two segments include an end of one of them.
  return std::min({segment_distance(p1, q1, q2), segment_distance(p2, q1, q2), segment_distance(q1, p1, p2),
                   segment_distance(q2, p1, p2)});
}

double polyline_length(const std::vector<Point>& points) {
  double length = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) length += distance(points[i - 1], points[i]);
  return length;
}

std::optional<mapping::MultiPolygon> with_bridges(const mapping::MultiPolygon& cspace,
                                                  const mapping::MultiPolygon& passages, const Point* robot) {
  auto outside = subtracted(passages, cspace);
  if (!outside) return std::nullopt;
  // The C-space's edges, each with the polygon it bounds. A part of the
  // passages outside the C-space shares its border with the polygons it
  // touches, up to the grid's rounding of the crossings (kTouchM).
  constexpr double kTouchM = 1e-4;
  struct BoundaryEdge {
    Point a, b;
    std::size_t polygon;
  };
  std::vector<BoundaryEdge> edges;
  std::vector<std::pair<mapping::Box, std::size_t>> boxes;
  for (std::size_t k = 0; k < cspace.size(); ++k) {
    auto add_ring = [&](const mapping::Ring& ring) {
      for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        const Point& a = ring[i];
        const Point& b = ring[i + 1];
        boxes.emplace_back(mapping::Box(Point(std::min(a.x(), b.x()), std::min(a.y(), b.y())),
                                        Point(std::max(a.x(), b.x()), std::max(a.y(), b.y()))),
                           edges.size());
        edges.push_back({a, b, k});
      }
    };
    add_ring(cspace[k].outer());
    for (const auto& hole : cspace[k].inners()) add_ring(hole);
  }
  const bgi::rtree<std::pair<mapping::Box, std::size_t>, bgi::rstar<16>> tree(boxes);

  mapping::MultiPolygon bridges;
  std::vector<std::size_t> touched;
  auto touch_from = [&](const mapping::Ring& ring) {
    for (const auto& v : ring) {
      const mapping::Box near(Point(v.x() - kTouchM, v.y() - kTouchM), Point(v.x() + kTouchM, v.y() + kTouchM));
      tree.query(bgi::intersects(near), boost::make_function_output_iterator([&](const auto& value) {
                   const BoundaryEdge& e = edges[value.second];
                   if (distance(v, closest_point_on_segment(v, e.a, e.b)) <= kTouchM &&
                       std::find(touched.begin(), touched.end(), e.polygon) == touched.end())
                     touched.push_back(e.polygon);
                 }));
      if (touched.size() >= 2) return;
    }
  };
  for (auto& part : *outside) {
    touched.clear();
    touch_from(part.outer());
    for (const auto& hole : part.inners())
      if (touched.size() < 2) touch_from(hole);
    if (touched.size() >= 2 || (robot && bg::covered_by(*robot, part))) bridges.push_back(std::move(part));
  }
  if (bridges.empty()) return cspace;
  return united(cspace, bridges);
}

std::vector<std::vector<Point>> way_near_or_outside(const mapping::MultiPolygon& cspace, const DrivenWay& way) {
  const auto& points = way.points;
  if (points.empty()) return {};
  // The whole way, when it is all outside (copied only then: it is kilometres long).
  auto all = [&] { return std::vector<Point>(points.begin(), points.end()); };
  mapping::Box box;
  bg::assign_inverse(box);
  std::size_t vertices = 0;
  for (const auto& polygon : cspace) {
    bg::expand(box, bg::return_envelope<mapping::Box>(polygon.outer()));
    vertices += polygon.outer().size();
  }
  if (vertices == 0) return {all()};  // no C-space: all of the way is outside it
  // A cell is marked when an edge of the C-space may come within `reach` of
  // it. An unmarked cell holds no point of the C-space's boundary: it is
  // wholly inside or wholly outside.
  const double reach = way.half_width_m + 1e-3;
  constexpr std::size_t kMaxCells = std::size_t{1} << 22;
  const double x0 = box.min_corner().x() - 2.0 * reach, y0 = box.min_corner().y() - 2.0 * reach;
  const double w = box.max_corner().x() - x0 + 2.0 * reach, h = box.max_corner().y() - y0 + 2.0 * reach;
  double cell = 0.25;
  if (w * h / (cell * cell) > static_cast<double>(kMaxCells)) cell = std::sqrt(w * h / static_cast<double>(kMaxCells));
  const int nx = static_cast<int>(std::ceil(w / cell)) + 1, ny = static_cast<int>(std::ceil(h / cell)) + 1;
  std::vector<char> marked(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), 0);
  auto clamp_x = [&](double x) { return std::clamp(static_cast<int>(std::floor((x - x0) / cell)), 0, nx - 1); };
  auto clamp_y = [&](double y) { return std::clamp(static_cast<int>(std::floor((y - y0) / cell)), 0, ny - 1); };
  // Calls f(cx, cy) for the cells of the boxes about the pieces (at most a
  // cell long) of segment a-b grown by r; false if one is off the grid.
  auto for_cells = [&](const Point& a, const Point& b, double r, auto&& f) {
    if (std::min(a.x(), b.x()) - r < x0 || std::min(a.y(), b.y()) - r < y0 ||
        std::max(a.x(), b.x()) + r >= x0 + nx * cell || std::max(a.y(), b.y()) + r >= y0 + ny * cell)
      return false;
    const int pieces = std::max(1, static_cast<int>(std::ceil(distance(a, b) / cell)));
    for (int k = 0; k < pieces; ++k) {
      const double t0 = static_cast<double>(k) / pieces, t1 = static_cast<double>(k + 1) / pieces;
      const double ax = a.x() + t0 * (b.x() - a.x()), ay = a.y() + t0 * (b.y() - a.y());
      const double bx = a.x() + t1 * (b.x() - a.x()), by = a.y() + t1 * (b.y() - a.y());
      const double lx = std::min(ax, bx) - r, hx = std::max(ax, bx) + r;
      const double ly = std::min(ay, by) - r, hy = std::max(ay, by) + r;
      for (int cy = clamp_y(ly); cy <= clamp_y(hy); ++cy)
        for (int cx = clamp_x(lx); cx <= clamp_x(hx); ++cx)
          if (!f(cx, cy)) return false;
    }
    return true;
  };
  auto at = [&](int cx, int cy) -> char& {
    return marked[static_cast<std::size_t>(cy) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(cx)];
  };
  auto mark_ring = [&](const mapping::Ring& ring) {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i)
      for_cells(ring[i], ring[i + 1], reach, [&](int cx, int cy) {
        at(cx, cy) = 1;
        return true;
      });
  };
  for (const auto& polygon : cspace) {
    mark_ring(polygon.outer());
    for (const auto& hole : polygon.inners()) mark_ring(hole);
  }
  // Whether an unmarked cell is inside: the parity of the C-space's edges
  // crossing its row's centre line left of its centre (all of its points
  // share the centre's answer). Each row's crossings, sorted when first asked.
  std::vector<std::vector<double>> row_crossings(static_cast<std::size_t>(ny));
  std::vector<char> row_sorted(static_cast<std::size_t>(ny), 0);
  auto add_crossings = [&](const mapping::Ring& ring) {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
      const Point& a = ring[i];
      const Point& b = ring[i + 1];
      const double lo = std::min(a.y(), b.y()), hi = std::max(a.y(), b.y());
      // Rows whose centre line y satisfies lo <= y < hi (a vertex on a
      // centre line counts once for the two edges that meet there).
      for (int cy = std::max(0, static_cast<int>(std::ceil((lo - y0) / cell - 0.5)));
           cy < ny && y0 + (cy + 0.5) * cell < hi; ++cy) {
        const double y = y0 + (cy + 0.5) * cell;
        if (y < lo) continue;  // rounding in the first row's index
        row_crossings[static_cast<std::size_t>(cy)].push_back(a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y()));
      }
    }
  };
  for (const auto& polygon : cspace) {
    add_crossings(polygon.outer());
    for (const auto& hole : polygon.inners()) add_crossings(hole);
  }
  auto cell_inside = [&](int cx, int cy) {
    auto& row = row_crossings[static_cast<std::size_t>(cy)];
    if (!row_sorted[static_cast<std::size_t>(cy)]) {
      std::sort(row.begin(), row.end());
      row_sorted[static_cast<std::size_t>(cy)] = 1;
    }
    const double x = x0 + (cx + 0.5) * cell;
    return (std::lower_bound(row.begin(), row.end(), x) - row.begin()) % 2 == 1;
  };
  // A piece of the way is dropped when every cell about it (grown by the
  // corridor's half-width) is unmarked and inside: its corridor then lies
  // in the C-space's interior.
  auto inside_clear = [&](const Point& a, const Point& b) {
    const bool clear = for_cells(a, b, reach, [&](int cx, int cy) { return at(cx, cy) == 0; });
    return clear && cell_inside(clamp_x(a.x()), clamp_y(a.y()));
  };
  std::vector<std::vector<Point>> stretches;
  if (points.size() == 1) {
    if (!inside_clear(points[0], points[0])) stretches.push_back(all());
    return stretches;
  }
  std::vector<Point> stretch;
  for (std::size_t i = 0; i + 1 < points.size(); ++i) {
    if (inside_clear(points[i], points[i + 1])) {
      if (!stretch.empty()) stretches.push_back(std::move(stretch));
      stretch.clear();
      continue;
    }
    if (stretch.empty()) stretch.push_back(points[i]);
    stretch.push_back(points[i + 1]);
  }
  if (!stretch.empty()) stretches.push_back(std::move(stretch));
  return stretches;
}

ConfigurationSpace::BuildResult ConfigurationSpace::build(const TypedMultiPolygon& free_space,
                                                          const CSpaceOptions& options, OffsetTileCache* cache,
                                                          const DrivenWay* way) {
  options_ = options;
  polygons_.clear();
  edges_.clear();
  reflex_nodes_.clear();
  reflex_edges_.clear();
  tree_.reset();
  build_grid();  // empty until the edges are in
  BuildResult result;
  if (!(options.robot_radius_m >= 0.0) || !(options.clearance_margin_m >= 0.0) ||
      !(options.interior_offset_m > 0.0) || options.points_per_circle < 4) {
    result.error = "bad C-space options";
    return result;
  }
  if (!mapping::types_match_rings(free_space)) {
    result.error = "map edge types do not match its rings";
    return result;
  }
  if (free_space.empty()) {
    result.ok = true;
    return result;
  }

  const double shrink_m = options.robot_radius_m + options.clearance_margin_m;
  if (shrink_m > 0.0) {
    InwardOffset how;
    how.distance_m = shrink_m;
    how.points_per_circle = options.points_per_circle;
    how.type_edges = options.edge_types;
    how.tile_m = options.offset_tile_m;
    how.tile_min_vertices = options.offset_tile_min_vertices;
    how.simplify_epsilon_m = options.simplify_epsilon_m;
    auto offset = options.boost_offset ? mapping::typed_offset(free_space, -shrink_m, options.points_per_circle)
                                       : offset_inward(free_space, how, cache);
    if (!offset.ok) {
      result.error = "offset by the robot radius failed: " + offset.error;
      return result;
    }
    polygons_ = std::move(offset.polygons);
    // offset_inward simplifies (a tiled polygon tile by tile), Boost's does not.
    if (options.boost_offset && options.simplify_epsilon_m > 0.0)
      polygons_ = mapping::simplify_typed(polygons_, options.simplify_epsilon_m);
  } else {
    polygons_ = free_space;
    if (options.simplify_epsilon_m > 0.0) polygons_ = mapping::simplify_typed(polygons_, options.simplify_epsilon_m);
  }
  // After the simplification: a bridge's narrow corridor would keep the
  // whole polygon it joins from being simplified (simplify_typed keeps a
  // polygon whole when simplifying it would make it invalid).
  if (way && !way->points.empty() && way->half_width_m > 0.0 &&
      std::all_of(way->points.begin(), way->points.end(), [](const Point& p) {
        return std::isfinite(p.x()) && std::isfinite(p.y()) && std::abs(p.x()) <= 1e9 && std::abs(p.y()) <= 1e9;
      })) {
    const auto cspace = mapping::geometry_of(polygons_);
    const auto passages = dilated_polylines(way_near_or_outside(cspace, *way), way->half_width_m);
    if (!passages.empty()) {
      // The way's newest point is where the robot stands (within a trail step).
      auto with_passages =
          with_bridges(cspace, passages, way->keep_where_the_robot_stands ? &way->points.back() : nullptr);
      if (!with_passages) {
        result.error = "a passage has a coordinate not finite or beyond 1e9 m";
        return result;
      }
      polygons_ = mapping::with_uniform_type(std::move(*with_passages), EdgeType::kObstacle);
    }
  }

  // Edges ring by ring, with repeated points dropped, linked to their neighbours.
  auto add_ring = [&](const mapping::Ring& ring, const std::vector<EdgeType>& types, std::uint32_t polygon) {
    std::vector<Point> points;
    std::vector<EdgeType> point_types;  // type of the edge starting at points[i]
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
      if (!points.empty() && bg::equals(points.back(), ring[i])) continue;
      points.push_back(ring[i]);
      point_types.push_back(types[i]);
    }
    while (points.size() > 1 && bg::equals(points.front(), points.back())) {
      points.pop_back();
      point_types.pop_back();
    }
    const std::size_t n = points.size();
    if (n < 3) return;
    const auto first = static_cast<std::uint32_t>(edges_.size());
    for (std::size_t i = 0; i < n; ++i) {
      const auto index = static_cast<std::uint32_t>(first + i);
      edges_.push_back(Edge{points[i], points[(i + 1) % n], point_types[i],
                            i == 0 ? static_cast<std::uint32_t>(first + n - 1) : index - 1,
                            i + 1 == n ? first : index + 1, polygon});
    }
  };
  for (std::uint32_t k = 0; k < polygons_.size(); ++k) {
    const auto& polygon = polygons_[k];
    add_ring(polygon.geometry.outer(), polygon.edge_types[0], k);
    for (std::size_t h = 0; h < polygon.geometry.inners().size(); ++h)
      add_ring(polygon.geometry.inners()[h], polygon.edge_types[1 + h], k);
  }

  max_x_ = -std::numeric_limits<double>::infinity();
  for (const Edge& e : edges_) max_x_ = std::max(max_x_, std::max(e.a.x(), e.b.x()));
  std::vector<Value> values;
  values.reserve(edges_.size());
  for (std::uint32_t i = 0; i < edges_.size(); ++i) values.emplace_back(box_of(edges_[i].a, edges_[i].b), i);
  tree_ = std::make_unique<Tree>(values.begin(), values.end());
  build_grid();

  // Reflex vertices: a right turn, because the free space is on the left.
  for (std::uint32_t i = 0; i < edges_.size(); ++i) {
    const Edge& in = edges_[i];
    const Edge& out = edges_[in.next];
    const double turn = orient(in.a, in.b, out.b) / (distance(in.a, in.b) * distance(out.a, out.b));
    if (!(turn < -1e-9)) continue;
    if (auto node = inward(in.b, i, /*at_vertex_b=*/true)) {
      reflex_nodes_.push_back(*node);
      reflex_edges_.push_back(i);
    }
  }
  result.ok = true;
  return result;
}

bool ConfigurationSpace::covers(const Point& p) const { return piece_of(p) >= 0; }

int ConfigurationSpace::piece_of(const Point& p) const {
  if (!tree_ || tree_->empty() || !std::isfinite(p.x()) || !std::isfinite(p.y())) return -1;
  // Parity of the boundary crossings of the ray from p towards +x: every ring
  // of edges_ is closed and the polygons are interior-disjoint, so an odd
  // count is inside (holes and polygons in holes included); and the first
  // boundary the ray crosses from inside a polygon is that polygon's own
  // (its outer ring or one of its holes). Only the edges whose boxes meet the
  // ray are looked at, so this costs about the edges along one line of the
  // map, not the whole map (bg::covered_by over every polygon, asked per
  // reflex vertex and per candidate, was most of a plan on ragged maps).
  const mapping::Box ray(p, Point(std::max(max_x_, p.x()) + 1.0, p.y()));
  bool inside = false;
  double nearest_x = std::numeric_limits<double>::infinity();
  std::uint32_t nearest_edge = 0;
  for (auto it = tree_->qbegin(bgi::intersects(ray)); it != tree_->qend(); ++it) {
    const Edge& e = edges_[it->second];
    const double o = orient(e.a, e.b, p);
    if (o == 0.0 && within_box(e.a, e.b, p)) return static_cast<int>(e.polygon);  // on the boundary
    // Half-open in y, so a crossing at a vertex is counted once.
    if ((e.a.y() > p.y()) == (e.b.y() > p.y()) || !((e.b.y() > e.a.y()) ? o > 0.0 : o < 0.0)) continue;
    inside = !inside;
    const double x = e.a.x() + (p.y() - e.a.y()) * (e.b.x() - e.a.x()) / (e.b.y() - e.a.y());
    // Ties (a vertex shared by two crossing edges) lie on one ring: either edge.
    if (x < nearest_x || (x == nearest_x && it->second < nearest_edge)) {
      nearest_x = x;
      nearest_edge = it->second;
    }
  }
  return inside ? static_cast<int>(edges_[nearest_edge].polygon) : -1;
}

double ConfigurationSpace::distance_to_boundary(const Point& p) const {
  double best = std::numeric_limits<double>::infinity();
  if (!tree_ || tree_->empty()) return best;
  // The edge of the nearest box bounds the answer, and every edge nearer
  // than that has its box within that distance of p. (Two cheap queries: an
  // incremental nearest query over all edges sorts them all, which made this
  // most of the C-space's build time.)
  for (auto it = tree_->qbegin(bgi::nearest(p, 1)); it != tree_->qend(); ++it) {
    const Edge& e = edges_[it->second];
    best = segment_distance(p, e.a, e.b);
  }
  const mapping::Box window(Point(p.x() - best, p.y() - best), Point(p.x() + best, p.y() + best));
  for (auto it = tree_->qbegin(bgi::intersects(window)); it != tree_->qend(); ++it) {
    const Edge& e = edges_[it->second];
    best = std::min(best, segment_distance(p, e.a, e.b));
  }
  return best;
}

std::vector<std::uint32_t> ConfigurationSpace::edges_near(const Point& p, double radius_m) const {
  std::vector<std::uint32_t> near;
  if (!tree_ || tree_->empty() || !std::isfinite(p.x()) || !std::isfinite(p.y()) || !(radius_m >= 0.0)) return near;
  const mapping::Box window(Point(p.x() - radius_m, p.y() - radius_m), Point(p.x() + radius_m, p.y() + radius_m));
  for (auto it = tree_->qbegin(bgi::intersects(window)); it != tree_->qend(); ++it) near.push_back(it->second);
  return near;
}

bool ConfigurationSpace::boundary_within(const Point& p, double radius_m) const {
  if (!tree_ || tree_->empty()) return false;
  // A small window (the nodes' and candidates' millimetre tests) looks at the
  // grid's few cells under it: an edge within radius_m of p has a point in
  // the window, and the grid lists it in the cell of that point. The rtree's
  // window query cost several times that.
  const int cx0 = cell_x(p.x() - radius_m), cx1 = cell_x(p.x() + radius_m);
  const int cy0 = cell_y(p.y() - radius_m), cy1 = cell_y(p.y() + radius_m);
  if (grid_nx_ > 0 && (cx1 - cx0 + 1) * (cy1 - cy0 + 1) <= 4) {
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) {
        const std::size_t c = static_cast<std::size_t>(cy) * static_cast<std::size_t>(grid_nx_) + static_cast<std::size_t>(cx);
        for (std::uint32_t k = grid_start_[c]; k < grid_start_[c + 1]; ++k) {
          const Edge& e = edges_[grid_edges_[k]];
          if (segment_distance(p, e.a, e.b) < radius_m) return true;
        }
      }
    return false;
  }
  // Every edge nearer than radius_m has its box in this window.
  const mapping::Box window(Point(p.x() - radius_m, p.y() - radius_m), Point(p.x() + radius_m, p.y() + radius_m));
  for (auto it = tree_->qbegin(bgi::intersects(window)); it != tree_->qend(); ++it) {
    const Edge& e = edges_[it->second];
    if (segment_distance(p, e.a, e.b) < radius_m) return true;
  }
  return false;
}

// Cells of about the edges' mean spacing (about as many cells as edges),
// each listing the edges that pass through it (for_cells_along).
void ConfigurationSpace::build_grid() {
  grid_start_.clear();
  grid_edges_.clear();
  grid_nx_ = grid_ny_ = 0;
  if (edges_.empty()) return;
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  for (const Edge& e : edges_) {
    x0 = std::min({x0, e.a.x(), e.b.x()});
    y0 = std::min({y0, e.a.y(), e.b.y()});
    x1 = std::max({x1, e.a.x(), e.b.x()});
    y1 = std::max({y1, e.a.y(), e.b.y()});
  }
  const double n = static_cast<double>(edges_.size());
  const double w = std::max(x1 - x0, 1e-6), h = std::max(y1 - y0, 1e-6);
  double cell = std::sqrt(w * h / n);
  cell = std::max({cell, std::max(w, h) / 4096.0, 1e-6});
  grid_x0_ = x0 - kGridSlack;
  grid_y0_ = y0 - kGridSlack;
  grid_cell_ = cell;
  grid_nx_ = static_cast<int>(std::floor((w + 2.0 * kGridSlack) / cell)) + 1;
  grid_ny_ = static_cast<int>(std::floor((h + 2.0 * kGridSlack) / cell)) + 1;
  const std::size_t cells = static_cast<std::size_t>(grid_nx_) * static_cast<std::size_t>(grid_ny_);
  grid_start_.assign(cells + 1, 0);
  for (const Edge& e : edges_)
    for_cells_along(e.a, e.b, [&](std::size_t c) {
      ++grid_start_[c + 1];
      return true;
    });
  for (std::size_t c = 0; c < cells; ++c) grid_start_[c + 1] += grid_start_[c];
  grid_edges_.resize(grid_start_[cells]);
  std::vector<std::uint32_t> fill(grid_start_.begin(), grid_start_.end() - 1);
  for (std::uint32_t i = 0; i < edges_.size(); ++i)
    for_cells_along(edges_[i].a, edges_[i].b, [&](std::size_t c) {
      grid_edges_[fill[c]++] = i;
      return true;
    });
}

// Column by column, the rows the segment's stretch in that column spans,
// each grown by kGridSlack: a superset of the cells the segment touches. An
// edge is listed in the cells along it and a segment test looks at the cells
// along the segment, so where they meet both see the cell of the meeting
// point. False as soon as fn(cell) is false.
template <class Fn>
bool ConfigurationSpace::for_cells_along(const Point& a, const Point& b, Fn&& fn) const {
  const double min_x = std::min(a.x(), b.x()), max_x = std::max(a.x(), b.x());
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  const int cx0 = cell_x(min_x - kGridSlack), cx1 = cell_x(max_x + kGridSlack);
  for (int cx = cx0; cx <= cx1; ++cx) {
    double ya = a.y(), yb = b.y();
    if (dx != 0.0) {
      const double xl = std::max(min_x, grid_x0_ + cx * grid_cell_);
      const double xr = std::min(max_x, grid_x0_ + (cx + 1) * grid_cell_);
      ya = a.y() + (xl - a.x()) / dx * dy;
      yb = a.y() + (xr - a.x()) / dx * dy;
    }
    const int cy0 = cell_y(std::min(ya, yb) - kGridSlack), cy1 = cell_y(std::max(ya, yb) + kGridSlack);
    for (int cy = cy0; cy <= cy1; ++cy)
      if (!fn(static_cast<std::size_t>(cy) * static_cast<std::size_t>(grid_nx_) + static_cast<std::size_t>(cx)))
        return false;
  }
  return true;
}

int ConfigurationSpace::cell_x(double x) const {
  return std::clamp(static_cast<int>(std::floor((x - grid_x0_) / grid_cell_)), 0, grid_nx_ - 1);
}
int ConfigurationSpace::cell_y(double y) const {
  return std::clamp(static_cast<int>(std::floor((y - grid_y0_) / grid_cell_)), 0, grid_ny_ - 1);
}

bool ConfigurationSpace::segment_free(const Point& a, const Point& b) const {
  ++segment_tests_;
  return meets_no_edge_but(a, b, kNoEdge, kNoEdge);
}

bool ConfigurationSpace::meets_no_edge_but(const Point& a, const Point& b, std::uint32_t skip_a,
                                           std::uint32_t skip_b) const {
  if (grid_nx_ == 0) return true;
  // Only the edges listed in the cells along the segment (some twice; the
  // answer is the same): the rtree's segment query was most of the path
  // matrix's time.
  return for_cells_along(a, b, [&](std::size_t c) {
    for (std::uint32_t k = grid_start_[c]; k < grid_start_[c + 1]; ++k) {
      const std::uint32_t i = grid_edges_[k];
      if (i == skip_a || i == skip_b) continue;
      if (segments_intersect(a, b, edges_[i].a, edges_[i].b)) return false;
    }
    return true;
  });
}

std::optional<Point> ConfigurationSpace::inward(const Point& q, std::uint32_t edge, bool at_vertex_b) const {
  const double delta = options_.interior_offset_m;
  Point direction;
  double step = delta;
  bool spike = false;
  if (at_vertex_b) {
    const Edge& in = edges_[edge];
    const Edge& out = edges_[in.next];
    const Point n1 = left_normal(in.a, in.b), n2 = left_normal(out.a, out.b);
    Point sum(n1.x() + n2.x(), n1.y() + n2.y());
    const double len = std::hypot(sum.x(), sum.y());
    if (len < 1e-9) {
      direction = n1;  // a spike: the edges run back on themselves
      spike = true;
    } else {
      direction = Point(sum.x() / len, sum.y() / len);
      // len / 2 is the sine of half the interior angle: at a sharp corner the
      // bisector must go further to get delta away from both edges.
      step = delta / std::max(len / 2.0, 0.1);
    }
  } else {
    direction = left_normal(edges_[edge].a, edges_[edge].b);
  }
  const Point candidate(q.x() + step * direction.x(), q.y() + step * direction.y());
  if (boundary_within(candidate, 0.5 * delta)) return std::nullopt;
  // The step leaves q into the interior side of the edges q lies on (left
  // of both at a vertex, as the bisector of their left normals is, unless
  // they run back on themselves): with no other edge met on the way, the
  // point is inside. That is a look at the grid cells along a few
  // millimetres, where covers() counts crossings along a ray across the
  // whole map, for every reflex vertex. Anything else on the way (another
  // ring touching q, a spike) goes to covers().
  const std::uint32_t skip_a = edge, skip_b = at_vertex_b ? edges_[edge].next : edge;
  if (!spike && meets_no_edge_but(q, candidate, skip_a, skip_b)) return candidate;
  if (!covers(candidate)) return std::nullopt;
  return candidate;
}

std::optional<Point> ConfigurationSpace::nearest_interior_point(const Point& p, double max_distance_m,
                                                               int skip_piece) const {
  if (!tree_ || !std::isfinite(p.x()) || !std::isfinite(p.y())) return std::nullopt;
  if (!boundary_within(p, 0.5 * options_.interior_offset_m) && covers(p) &&
      (skip_piece < 0 || piece_of(p) != skip_piece))
    return p;
  const mapping::Box window(Point(p.x() - max_distance_m, p.y() - max_distance_m),
                            Point(p.x() + max_distance_m, p.y() + max_distance_m));
  struct Near {
    double d;
    std::uint32_t edge;
    Point q;
  };
  auto within = [&](auto&& each) {
    for (auto it = tree_->qbegin(bgi::intersects(window)); it != tree_->qend(); ++it) {
      const Edge& e = edges_[it->second];
      if (skip_piece >= 0 && e.polygon == static_cast<std::uint32_t>(skip_piece)) continue;
      const Point q = closest_point_on_segment(p, e.a, e.b);
      const double d = distance(p, q);
      if (d <= max_distance_m) each(Near{d, it->second, q});
    }
  };
  // Ties go to the lower edge index: the answer does not depend on the tree's order.
  auto before = [](const Near& a, const Near& b) { return a.d < b.d || (a.d == b.d && a.edge < b.edge); };
  std::optional<Near> best;
  within([&](const Near& n) {
    if (!best || before(n, *best)) best = n;
  });
  if (!best) return std::nullopt;
  auto moved_in = [&](const Near& n) {
    const Edge& e = edges_[n.edge];
    if (bg::equals(n.q, e.b)) return inward(n.q, n.edge, true);
    if (bg::equals(n.q, e.a)) return inward(n.q, e.prev, true);
    return inward(n.q, n.edge, false);
  };
  if (auto in = moved_in(*best)) return in;
  // The nearest boundary point has no interior beside it: a sliver of
  // C-space thinner than interior_offset_m (a piece of no area, a neck).
  // Then the next nearest edges, in order, until one has (session 45: a
  // sliver's edge nearest a frontier left it "with no C-space near" while a
  // room's C-space lay 2 m from it, in view). Only then: the usual answer
  // costs no more than it did.
  std::vector<Near> near;
  within([&](const Near& n) { near.push_back(n); });
  // At most kMaxTries of them, so that a map of many slivers (hostile input)
  // costs a bounded search per call.
  constexpr std::size_t kMaxTries = 256;
  std::sort(near.begin(), near.end(), before);
  for (std::size_t k = 1; k < near.size() && k <= kMaxTries; ++k)
    if (auto in = moved_in(near[k])) return in;
  return std::nullopt;
}

}  // namespace pex::planning
