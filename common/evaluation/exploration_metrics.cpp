#include "evaluation/exploration_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include <boost/geometry/geometries/multi_point.hpp>

#include "geometry/point.hpp"

namespace pex::evaluation {

namespace bg = boost::geometry;
using mapping::Box;
using mapping::MultiPolygon;
using mapping::Point;
using mapping::Polygon;
using mapping::Ring;

namespace {
bool plausible(const MultiPolygon& a, const MultiPolygon& b, const MultiPolygon& result, mapping::OverlayOp op);
}  // namespace

std::optional<MultiPolygon> checked_overlay(const MultiPolygon& a, const MultiPolygon& b, mapping::OverlayOp op) {
  // Our edge overlay first: it takes the shared and collinear edges of
  // neighbouring capsules in its stride; Boost.Geometry's overlay (without
  // rescaling, BOOST_GEOMETRY_NO_ROBUSTNESS) drops pieces on such input.
  const auto ours = mapping::overlay(mapping::with_uniform_type(a, mapping::EdgeType::kObstacle),
                                     mapping::with_uniform_type(b, mapping::EdgeType::kObstacle), op);
  if (ours.ok) {
    MultiPolygon result = mapping::geometry_of(ours.polygons);
    if (plausible(a, b, result, op)) return result;
  }
  try {
    MultiPolygon result;
    switch (op) {
      case mapping::OverlayOp::kUnion: bg::union_(a, b, result); break;
      case mapping::OverlayOp::kIntersection: bg::intersection(a, b, result); break;
      case mapping::OverlayOp::kDifference: bg::difference(a, b, result); break;
    }
    if (plausible(a, b, result, op)) return result;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Offsets of the disk polygon's vertices at fixed world angles k * 2 pi / n,
// exact at multiples of 90 degrees and exactly opposite for k and k + n / 2,
// so capsules around one point share their vertices bit for bit.
std::vector<Point> disk_offsets(double radius_m, int n) {
  n = std::max(8, (n + 3) / 4 * 4);
  std::vector<Point> offsets(static_cast<std::size_t>(n));
  const int quarter = n / 4;
  for (int k = 0; k < n / 2; ++k) {
    double c, s;
    if (k % quarter == 0) {
      const int q = k / quarter;  // 0 or 1
      c = q == 0 ? 1.0 : 0.0;
      s = q == 0 ? 0.0 : 1.0;
    } else {
      const double angle = 2 * std::numbers::pi * k / n;
      c = std::cos(angle), s = std::sin(angle);
    }
    offsets[static_cast<std::size_t>(k)] = Point(radius_m * c, radius_m * s);
    offsets[static_cast<std::size_t>(k + n / 2)] = Point(-radius_m * c, -radius_m * s);
  }
  return offsets;
}

// The segment a-b grown by the disk: the convex hull of the disk polygons at
// both ends (a disk polygon when a == b).
Polygon capsule(const Point& a, const Point& b, const std::vector<Point>& offsets) {
  bg::model::multi_point<Point> points;
  points.reserve(2 * offsets.size());
  for (const auto& o : offsets) {
    points.emplace_back(a.x() + o.x(), a.y() + o.y());
    if (a.x() != b.x() || a.y() != b.y()) points.emplace_back(b.x() + o.x(), b.y() + o.y());
  }
  Polygon hull;
  bg::convex_hull(points, hull);
  bg::correct(hull);
  return hull;
}

// Whether `result` can be a op b: valid, and its area within the bounds the
// operation allows (a dropped or doubled piece breaks them).
bool plausible(const MultiPolygon& a, const MultiPolygon& b, const MultiPolygon& result, mapping::OverlayOp op) {
  if (!bg::is_valid(result)) return false;
  const double area_a = bg::area(a), area_b = bg::area(b), area_r = bg::area(result);
  const double eps = 1e-9 * (area_a + area_b) + 1e-12;
  switch (op) {
    case mapping::OverlayOp::kUnion:
      return area_r >= std::max(area_a, area_b) - eps && area_r <= area_a + area_b + eps;
    case mapping::OverlayOp::kIntersection:
      return area_r >= -eps && area_r <= std::min(area_a, area_b) + eps;
    case mapping::OverlayOp::kDifference:
      return area_r >= area_a - area_b - eps && area_r <= area_a + eps;
  }
  return false;
}

MultiPolygon overlay_or_throw(const MultiPolygon& a, const MultiPolygon& b, mapping::OverlayOp op) {
  if (auto r = checked_overlay(a, b, op)) return std::move(*r);
  throw std::runtime_error("exploration metrics: a polygon overlay failed (edge overlay and Boost.Geometry)");
}

// Union of many polygons, two by two in rounds (a balanced tree), so each
// overlay joins pieces of similar size and neighbouring input (walls along
// a line string, edges along a ring) meet early.
MultiPolygon union_cascade(std::vector<MultiPolygon> parts) {
  if (parts.empty()) return {};
  while (parts.size() > 1) {
    std::vector<MultiPolygon> next;
    next.reserve((parts.size() + 1) / 2);
    for (std::size_t i = 0; i + 1 < parts.size(); i += 2)
      next.push_back(overlay_or_throw(parts[i], parts[i + 1], mapping::OverlayOp::kUnion));
    if (parts.size() % 2 == 1) next.push_back(std::move(parts.back()));
    parts = std::move(next);
  }
  return std::move(parts.front());
}

std::optional<MultiPolygon> union_or_nullopt(std::vector<MultiPolygon> parts) {
  try {
    return union_cascade(std::move(parts));
  } catch (const std::runtime_error&) {
    return std::nullopt;
  }
}

MultiPolygon walls_box(const sim::World& world) {
  Polygon box;
  bg::convert(Box(Point(world.min_x, world.min_y), Point(world.max_x, world.max_y)), box);
  bg::correct(box);
  return {box};
}

}  // namespace

MultiPolygon configuration_free_component(const sim::World& world, double robot_radius_m,
                                          const geometry::Pose2& start, const ReachableOptions& options) {
  if (!(robot_radius_m > 0.0) || world.walls.empty()) return {};
  const auto offsets = disk_offsets(robot_radius_m, options.points_per_circle);

  // Obstacles for the robot's centre: every wall grown by the disk.
  std::vector<MultiPolygon> capsules;
  capsules.reserve(world.walls.size());
  for (const auto& w : world.walls) capsules.push_back({capsule(Point(w.x0, w.y0), Point(w.x1, w.y1), offsets)});
  const MultiPolygon blocked = union_cascade(std::move(capsules));

  // C-free within the walls' box grown by a margin wide enough for the robot
  // to pass round the outside of the walls.
  const double margin = 2 * robot_radius_m + 1.0;
  Polygon region;
  bg::convert(Box(Point(world.min_x - margin, world.min_y - margin), Point(world.max_x + margin, world.max_y + margin)),
              region);
  bg::correct(region);
  MultiPolygon cfree = overlay_or_throw(MultiPolygon{region}, blocked, mapping::OverlayOp::kDifference);

  const Point s(start.x_m, start.y_m);
  for (auto& polygon : cfree)
    if (bg::covered_by(s, polygon)) return MultiPolygon{std::move(polygon)};
  return {};
}

MultiPolygon reachable_free_space(const sim::World& world, double robot_radius_m, const geometry::Pose2& start,
                                  const ReachableOptions& options) {
  const MultiPolygon component = configuration_free_component(world, robot_radius_m, start, options);
  if (component.empty()) return {};
  const auto offsets = disk_offsets(robot_radius_m, options.points_per_circle);

  // Minkowski sum with the disk: the component plus a capsule on each of its
  // boundary edges (a point is within r of the component iff it is in it or
  // within r of its boundary).
  std::vector<MultiPolygon> parts;
  auto add_ring = [&](const Ring& ring) {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) parts.push_back({capsule(ring[i], ring[i + 1], offsets)});
  };
  for (const auto& polygon : component) {
    add_ring(polygon.outer());
    for (const auto& inner : polygon.inners()) add_ring(inner);
  }
  // Edges in ring order: the cascade unites neighbouring capsules first.
  const MultiPolygon band = union_cascade(std::move(parts));
  const MultiPolygon swept = overlay_or_throw(component, band, mapping::OverlayOp::kUnion);
  return overlay_or_throw(swept, walls_box(world), mapping::OverlayOp::kIntersection);
}

MultiPolygon to_world(const MultiPolygon& in_map, const geometry::Pose2& map_in_world) {
  const geometry::PoseTransform move(map_in_world);
  MultiPolygon out = in_map;
  for (auto& polygon : out) {
    for (auto& p : polygon.outer()) p = move(p);
    for (auto& inner : polygon.inners())
      for (auto& p : inner) p = move(p);
  }
  return out;  // a rigid motion keeps orientation and validity
}

mapping::TypedMultiPolygon to_world(const mapping::TypedMultiPolygon& in_map, const geometry::Pose2& map_in_world) {
  mapping::TypedMultiPolygon out = in_map;
  for (auto& polygon : out) polygon.geometry = to_world(MultiPolygon{polygon.geometry}, map_in_world).front();
  return out;
}

namespace {

// area(a ∩ b), with a partition check: area(a ∩ b) + area(a - b) = area(a).
// NaN when the overlays fail.
double intersection_area(const MultiPolygon& a, const MultiPolygon& b) {
  const auto inter = checked_overlay(a, b, mapping::OverlayOp::kIntersection);
  const auto rest = checked_overlay(a, b, mapping::OverlayOp::kDifference);
  if (!inter || !rest) return kNaN;
  const double area_a = bg::area(a), area_inter = bg::area(*inter);
  if (std::abs(area_inter + bg::area(*rest) - area_a) > 1e-6 * area_a + 1e-9) return kNaN;
  return area_inter;
}

}  // namespace

double coverage(const MultiPolygon& map_free, const MultiPolygon& reachable) {
  const double reachable_m2 = bg::area(reachable);
  if (!(reachable_m2 > 0.0)) return kNaN;
  return intersection_area(map_free, reachable) / reachable_m2;
}

double iou(const MultiPolygon& map_free, const MultiPolygon& reachable) {
  // |A ∪ B| = |A| + |B| - |A ∩ B|: one overlay, so the two areas agree.
  const double inter = intersection_area(map_free, reachable);
  const double uni = bg::area(map_free) + bg::area(reachable) - inter;
  return uni > 0.0 ? inter / uni : kNaN;
}

MapScore score_map(const mapping::TypedMultiPolygon& map, const geometry::Pose2& map_in_world,
                   const MultiPolygon& reachable, const WallIndex& walls, double wall_tolerance_m,
                   double obstacle_band_credit_m, CreditNear credit_near) {
  MapScore score;
  const mapping::TypedMultiPolygon typed_world = to_world(map, map_in_world);
  MultiPolygon free_world = mapping::geometry_of(typed_world);
  score.explored_m2 = bg::area(free_world);
  score.reachable_m2 = bg::area(reachable);
  score.obstacle_on_wall = obstacle_on_wall(typed_world, walls, wall_tolerance_m);
  if (obstacle_band_credit_m > 0.0) {
    // The map plus the reachable space within the credit of an obstacle edge
    // (or of a wall).
    const auto offsets = disk_offsets(obstacle_band_credit_m, 16);
    std::vector<MultiPolygon> capsules;
    if (credit_near == CreditNear::kWorldWalls) {
      for (const auto& w : walls.walls()) capsules.push_back({capsule(Point(w.x0, w.y0), Point(w.x1, w.y1), offsets)});
    } else {
      mapping::for_each_edge(typed_world, [&](const Point& a, const Point& b, mapping::EdgeType t) {
        if (t == mapping::EdgeType::kObstacle) capsules.push_back({capsule(a, b, offsets)});
      });
    }
    const auto band = checked_overlay(union_or_nullopt(std::move(capsules)).value_or(MultiPolygon{}), reachable,
                                      mapping::OverlayOp::kIntersection);
    const auto credited = band ? checked_overlay(free_world, *band, mapping::OverlayOp::kUnion) : std::nullopt;
    if (!credited) {
      score.mapped_reachable_m2 = score.coverage = score.iou = kNaN;
      return score;
    }
    free_world = *credited;
  }
  score.mapped_reachable_m2 = intersection_area(free_world, reachable);
  score.coverage = score.reachable_m2 > 0.0 ? score.mapped_reachable_m2 / score.reachable_m2 : kNaN;
  const double uni = bg::area(free_world) + score.reachable_m2 - score.mapped_reachable_m2;
  score.iou = uni > 0.0 ? score.mapped_reachable_m2 / uni : kNaN;
  return score;
}

}  // namespace pex::evaluation
