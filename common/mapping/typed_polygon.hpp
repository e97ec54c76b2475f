#pragma once
// Typed polygons: polygons with holes (Boost.Geometry) whose every edge carries
// a type, obstacle or frontier (paper, section "Polygonal domain").
//
// Coordinates are double metres in the map frame (docs/mapping.md says why).
// Rings are closed (the last point repeats the first) and oriented as the MAP
// message wants them: outer rings counter-clockwise, holes clockwise, so the
// free space is always on the left of an edge.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/box.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#include <boost/geometry/geometries/multi_polygon.hpp>
#include <boost/geometry/geometries/segment.hpp>

#include "geometry/point.hpp"

namespace pex::mapping {

namespace bg = boost::geometry;

using geometry::Point;
using geometry::Segment;
using Polygon = bg::model::polygon<Point, /*ClockWise=*/false, /*Closed=*/true>;
using Ring = Polygon::ring_type;
using MultiPolygon = bg::model::multi_polygon<Polygon>;
using Box = bg::model::box<Point>;

// The type of one edge. kBorder marks an artificial edge on the box of a map
// tile (PolygonMap clips the map into tiles); it never leaves PolygonMap.
enum class EdgeType : std::uint8_t { kObstacle = 0, kFrontier = 1, kBorder = 2 };

const char* to_string(EdgeType type);

// A polygon with holes and one type per edge.
// Contract: edge_types.size() == 1 + geometry.inners().size(); edge_types[0]
// belongs to the outer ring, edge_types[1 + k] to hole k; entry i of a ring is
// the type of the edge from point i to point i + 1, so a closed ring of n + 1
// points (n distinct vertices) has n types.
struct TypedPolygon {
  Polygon geometry;
  std::vector<std::vector<EdgeType>> edge_types;
};
using TypedMultiPolygon = std::vector<TypedPolygon>;

// True if the type arrays match the rings (see TypedPolygon's contract).
bool types_match_rings(const TypedPolygon& polygon);
bool types_match_rings(const TypedMultiPolygon& polygons);

// Boost.Geometry validity of the geometry plus types_match_rings. `why`, if
// given, receives Boost's reason on failure.
bool is_valid(const TypedPolygon& polygon, std::string* why = nullptr);
bool is_valid(const TypedMultiPolygon& polygons, std::string* why = nullptr);
// The same verdict for one polygon, is_clearly_valid asked first (below):
// Boost only for what the cheap test cannot vouch for. For polygons checked
// as they come (scans, decoded map messages).
bool is_valid_cheap_first(const TypedPolygon& polygon, std::string* why = nullptr);

// Even-odd (crossing number) point-in-ring test, independent of the ring's
// orientation (holes are stored clockwise in the counter-clockwise ring
// type). For points known to be off the ring's boundary.
bool inside_ring(const Point& p, const Ring& ring);

// The crossing-number rule for one edge: true if the ray from p towards +x
// crosses edge a-b (half-open in y, so a vertex on the ray counts once).
inline bool ray_crosses(const Point& p, const Point& a, const Point& b) {
  return (a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x();
}

// A sufficient test of validity, several times cheaper than bg::is_valid:
// true only when every ring is closed, has at least 3 distinct vertices, no
// repeated consecutive point and the right orientation, no two edges of any
// rings come within the clearance of each other except consecutive edges at their
// shared vertex (no crossing, no touching, no spike), every hole lies inside
// its own outer ring and outside its siblings, and no polygon lies inside
// another except inside one of its holes. The clearance is 4e-8 of the
// larger side of the box of all the rings, at least 1e-7 m. Such a
// multi-polygon is valid by OGC's rules; bg::is_valid, which merges features
// below about 1e-7 of that side, may still call a feature between the two a
// spike (typed_polygon.cpp). false means "not shown": the caller asks bg::is_valid, which
// also accepts rings touching at points. Used where validity is checked on
// every insert (PolygonMap); tests keep bg::is_valid (is_valid above).
// When it returns false and `unclear` is given, *unclear names the polygons
// (indices into `polygons`) of the first feature it could not clear: the
// same index twice for one polygon alone (a short edge, a crossing of its
// own rings), two for a pair too close to each other.
struct UnclearPolygons {
  std::size_t first = 0, second = 0;
};
bool is_clearly_valid(std::span<const TypedPolygon> polygons, UnclearPolygons* unclear = nullptr);
// is_clearly_valid first; what it cannot show (rings touching at points,
// features near Boost's tolerance) bg::is_valid decides, saying why in `why`
// when invalid. Edge types are not looked at.
bool is_valid_cheap_first(std::span<const TypedPolygon> polygons, std::string& why);

// Number of distinct vertices (a closed ring of n + 1 points counts n).
std::size_t vertex_count(const Polygon& polygon);
std::size_t vertex_count(const MultiPolygon& polygons);
std::size_t vertex_count(const TypedMultiPolygon& polygons);

double area(const TypedMultiPolygon& polygons);
// Total length of the edges of one type.
double edge_length(const TypedMultiPolygon& polygons, EdgeType type);

MultiPolygon geometry_of(const TypedMultiPolygon& polygons);
// Every edge gets `type` (used for inputs whose origin alone decides the type).
TypedMultiPolygon with_uniform_type(const MultiPolygon& polygons, EdgeType type);

// Heap bytes held by the geometry and types (for memory figures).
std::size_t memory_bytes(const TypedMultiPolygon& polygons);

// Visits every edge: fn(a, b, type).
template <class Fn>
void for_each_edge(const TypedPolygon& polygon, Fn&& fn) {
  auto visit_ring = [&](const Ring& ring, const std::vector<EdgeType>& types) {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i) fn(ring[i], ring[i + 1], types[i]);
  };
  visit_ring(polygon.geometry.outer(), polygon.edge_types[0]);
  for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
    visit_ring(polygon.geometry.inners()[k], polygon.edge_types[1 + k]);
}
template <class Fn>
void for_each_edge(const TypedMultiPolygon& polygons, Fn&& fn) {
  for (const auto& p : polygons) for_each_edge(p, fn);
}

// Ramer-Douglas-Peucker on every ring, never across a change of edge type: a
// ring is cut into runs of equal type and each run is simplified with its
// end points fixed, so an obstacle edge is never merged with a frontier edge.
// Before that, edges shorter than 1e-3 epsilon_m are merged into a neighbour
// (their type is lost; a vertex of a border edge never moves, except that a
// short edge cutting off a corner between two border edges becomes that
// corner), and holes whose box is smaller than that are dropped. The
// boundary moves by at most epsilon_m.
// A simplification that would make a polygon invalid is not applied to that
// polygon (it is kept as it was). epsilon_m <= 0 returns the input unchanged.
// check_each_polygon = false skips that per-polygon check, for callers that
// check the whole result anyway (PolygonMap: is_valid is the costliest step).
TypedMultiPolygon simplify_typed(std::span<const TypedPolygon> polygons, double epsilon_m,
                                 bool check_each_polygon = true);

// Indices of the points RDP keeps from points[first..last] (both kept).
void rdp_keep(const std::vector<Point>& points, std::size_t first, std::size_t last,
              double epsilon_m, std::vector<bool>& keep);
// RDP on a closed ring: points[0..n], points[n] == points[0]. keep[i] true
// (keep[0] and keep[n] among them) fixes vertex i; between consecutive fixed
// vertices, the vertices RDP keeps are marked. With only vertex 0 fixed, the
// vertex farthest from it is fixed too, so both halves are open chains.
void rdp_keep_ring(const std::vector<Point>& points, double epsilon_m, std::vector<bool>& keep);

}  // namespace pex::mapping
