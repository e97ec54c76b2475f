#pragma once
// The configuration space of a disk robot: the free space of the planning map
// shrunk by the robot's radius (paper, "Polygon offsetting"), with an index of
// its boundary edges for segment and nearest-point queries.
//
// A point of the C-space is a position of the robot's centre at which the
// robot's disk touches no edge of the map (obstacle or frontier: the robot
// stays out of unknown space too). A segment between two C-space points is a
// motion the robot can make when it crosses no C-space boundary edge.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <boost/geometry/index/rtree.hpp>

#include "mapping/typed_ops.hpp"
#include "mapping/typed_polygon.hpp"
#include "planning/inward_offset.hpp"

namespace pex::planning {

using mapping::EdgeType;
using mapping::Point;
using mapping::TypedMultiPolygon;

// The way the robot drove (its centre's positions, oldest first) and the
// corridor of half_width_m about it that the C-space keeps open
// (ConfigurationSpace::build, driven_trail.hpp: the one certain proof of
// where the robot's disk fits). A view of the points: they outlive the build.
struct DrivenWay {
  std::span<const Point> points;
  double half_width_m = 0.0;
  // Keep also the corridor's part about the newest point (where the robot
  // stands) when it joins no two pieces: for a robot farther outside the
  // C-space than a plan's start may snap (with_bridges).
  bool keep_where_the_robot_stands = false;
};

struct CSpaceOptions {
  double robot_radius_m = 0.25;
  // Added to the radius: the planned clearance from every map edge is
  // robot_radius_m + clearance_margin_m - simplify_epsilon_m at least.
  double clearance_margin_m = 0.05;
  // Vertices of the round joins the offset puts around the map's corners.
  int points_per_circle = 16;
  // Ramer-Douglas-Peucker tolerance of the offset (0 = off): fewer
  // vertices, fewer graph nodes. A tiled polygon is simplified tile by tile
  // before the tiles' union (InwardOffset::simplify_epsilon_m), to the same
  // bound.
  double simplify_epsilon_m = 0.01;
  // Graph nodes on the boundary (reflex vertices, snapped candidates) are
  // moved this far into the interior, so segment tests between them never
  // have to decide a touch at an end point.
  double interior_offset_m = 1e-3;
  // true: each C-space edge typed as the map edge it was offset from
  // (mapping::assign_types), for whoever draws or reads the C-space's types.
  // false: every edge kObstacle. Planning reads no C-space edge type (the
  // frontiers come from the map) and typing was a fifth of a plan's time on
  // campus (docs/exploration.md, "Planning time").
  bool edge_types = false;
  // true: offset with Boost.Geometry's buffer (mapping::typed_offset), the
  // reference the tests compare offset_inward() with; several times slower
  // on ragged real maps.
  bool boost_offset = false;
  // The offset of a polygon of at least offset_tile_min_vertices is computed
  // in square tiles of offset_tile_m (0: every polygon whole), which a cache
  // passed to build() keeps between plans (inward_offset.hpp).
  double offset_tile_m = 12.0;
  int offset_tile_min_vertices = 400;
};

class ConfigurationSpace {
 public:
  struct Edge {
    Point a, b;
    EdgeType type;        // the type of the map edge it was offset from
    std::uint32_t prev;   // edge ending at a (same ring)
    std::uint32_t next;   // edge starting at b (same ring)
    std::uint32_t polygon;  // index into polygons(): the connected piece it bounds
  };

  struct BuildResult {
    bool ok = false;
    std::string error;  // why not ok (offset failed, empty map, ...)
  };

  // Offsets `free_space` (outer rings counter-clockwise, holes clockwise:
  // free space on the left of every edge) inward by the robot radius plus
  // margin. An empty result (the map is narrower than the robot) is ok: the
  // C-space is simply empty. `cache` (may be null) keeps offset tiles from
  // one build to the next; the C-space does not depend on it. `way` (may
  // be null or empty): its corridor is positions of the robot's centre
  // known to be free whatever the map says; those of its parts that join
  // two pieces of the C-space (and, with keep_where_the_robot_stands, the
  // part holding its newest point) are united into it after the offset
  // (with_bridges); their edges are typed kObstacle. A way with a point
  // not finite or beyond 1e9 m adds nothing.
  BuildResult build(const TypedMultiPolygon& free_space, const CSpaceOptions& options,
                    OffsetTileCache* cache = nullptr, const DrivenWay* way = nullptr);

  const TypedMultiPolygon& polygons() const { return polygons_; }
  const std::vector<Edge>& edges() const { return edges_; }
  const CSpaceOptions& options() const { return options_; }
  bool empty() const { return polygons_.empty(); }

  // True if p is inside or on the boundary.
  bool covers(const Point& p) const;
  // The index into polygons() of the piece p is inside or on the boundary
  // of, -1 if none: a polygon of the C-space is one connected piece, so two
  // points are joined by a path in the C-space if and only if they are in
  // the same piece. Costs about the edges along one line, not the map.
  int piece_of(const Point& p) const;
  // Distance from p to the nearest boundary edge (+inf if there is none).
  double distance_to_boundary(const Point& p) const;
  // distance_to_boundary(p) < radius_m, from the edges near p only (no
  // nearest-edge search: the nodes' and candidates' interior test).
  bool boundary_within(const Point& p, double radius_m) const;
  // The boundary edges (indices into edges()) whose bounding boxes meet the
  // square of half-width radius_m around p, in no particular order: every
  // edge within radius_m of p is among them. From the edges' index, not the
  // rings: what is near a point of a big map costs about what is there.
  std::vector<std::uint32_t> edges_near(const Point& p, double radius_m) const;
  // True if the segment a-b crosses or touches no boundary edge. With both
  // ends in the C-space's interior this means the whole segment is in it.
  bool segment_free(const Point& a, const Point& b) const;

  // A point of the interior within `max_distance_m` of p, at least about
  // interior_offset_m from the boundary: p itself if it is such a point, else
  // the nearest boundary point moved inward. nullopt if there is none.
  // With `skip_piece` (an index into polygons()), a point of any other piece.
  std::optional<Point> nearest_interior_point(const Point& p, double max_distance_m, int skip_piece = -1) const;

  // The reflex vertices (interior angle > 180 degrees), each moved
  // interior_offset_m inward along its bisector: the nodes through which
  // shortest paths bend.
  const std::vector<Point>& reflex_nodes() const { return reflex_nodes_; }
  // Parallel to reflex_nodes(): the boundary edge ending at the node's vertex
  // (edges()[e] comes in, edges()[edges()[e].next] goes out). The node is
  // where both edges' parallels at interior_offset_m meet (the step is capped
  // at sharp spikes), so these edges also give the boundary's directions at
  // the node.
  const std::vector<std::uint32_t>& reflex_edges() const { return reflex_edges_; }

  // Segment tests done so far (for statistics).
  std::int64_t segment_tests() const { return segment_tests_; }

 private:
  using Box = mapping::Box;
  using Value = std::pair<Box, std::uint32_t>;
  using Tree = boost::geometry::index::rtree<Value, boost::geometry::index::rstar<16>>;

  std::optional<Point> inward(const Point& q, std::uint32_t edge, bool at_vertex_b) const;
  // True if the segment a-b meets no boundary edge but skip_a and skip_b
  // (kNoEdge: none skipped), looking at the grid cells along it.
  static constexpr std::uint32_t kNoEdge = 0xffffffffu;
  bool meets_no_edge_but(const Point& a, const Point& b, std::uint32_t skip_a, std::uint32_t skip_b) const;
  void build_grid();
  template <class Fn>
  bool for_cells_along(const Point& a, const Point& b, Fn&& fn) const;
  int cell_x(double x) const;  // clamped to the grid
  int cell_y(double y) const;
  // Cells are looked at this much beyond where a segment or an edge box
  // reaches, so rounding at cell borders never leaves out a cell.
  static constexpr double kGridSlack = 1e-6;

  CSpaceOptions options_;
  TypedMultiPolygon polygons_;
  std::vector<Edge> edges_;
  std::vector<Point> reflex_nodes_;
  std::vector<std::uint32_t> reflex_edges_;
  std::unique_ptr<Tree> tree_;
  double max_x_ = 0.0;  // of every boundary edge: where covers()'s ray ends
  // Uniform grid over the boundary edges for segment_free(): cell (cx, cy)
  // lists grid_edges_[grid_start_[c] .. grid_start_[c + 1]), c = cy * nx + cx.
  double grid_x0_ = 0.0, grid_y0_ = 0.0, grid_cell_ = 1.0;
  int grid_nx_ = 0, grid_ny_ = 0;
  std::vector<std::uint32_t> grid_start_;
  std::vector<std::uint32_t> grid_edges_;
  mutable std::int64_t segment_tests_ = 0;
};

// `cspace` with the parts of `passages` outside it that join two or more of
// its polygons united in: the bridges across gaps the map has shut. A part
// that touches one polygon only (a trail running a little outside the
// C-space along a wall, or into a nook) adds no place the robot can get to,
// only vertices that every plan would pay for, and is left out, unless it
// holds `robot` (may be null): the robot stands in that nook, and the part
// is its way back into the C-space (campus: a way in, then SLAM moved the
// pose 0.37 m, the robot 0.54 m outside the C-space, the mission FAILED on
// five plans that could not start). nullopt: a coordinate not finite or
// beyond 1e9 m.
std::optional<mapping::MultiPolygon> with_bridges(const mapping::MultiPolygon& cspace,
                                                  const mapping::MultiPolygon& passages,
                                                  const Point* robot = nullptr);

// The stretches of `way` whose corridor may reach out of `cspace`: the rest
// of it runs inside, farther than half_width_m (and 1 mm) from every edge of
// `cspace`, so its corridor adds nothing there. A robot at the end of a long
// mission has driven kilometres, nearly all of it well inside the C-space;
// the corridor of all of it took two thirds of a tight plan's CPU (campus,
// `pex-plan --every-map --tight`, docs/exploration.md "Planning time").
// Conservative: a stretch is kept unless a grid of the edges shows it clear.
// Each stretch is a polyline of two or more points of `way` (one, for a way
// of one point); every point of `way` is assumed finite.
std::vector<std::vector<Point>> way_near_or_outside(const mapping::MultiPolygon& cspace, const DrivenWay& way);

// Small geometry helpers shared by the planning code.
double distance(const Point& a, const Point& b);
// The point of segment a-b closest to p.
Point closest_point_on_segment(const Point& p, const Point& a, const Point& b);
// True if the closed segments p1-p2 and q1-q2 share a point.
bool segments_intersect(const Point& p1, const Point& p2, const Point& q1, const Point& q2);
// The unit normal on the left of the direction a -> b (the free side of a
// map or C-space edge); (0, 0) when a == b.
Point left_normal(const Point& a, const Point& b);
// Distance between the closed segments p1-p2 and q1-q2 (0 if they share a point).
double segment_distance(const Point& p1, const Point& p2, const Point& q1, const Point& q2);
// Length of a polyline.
double polyline_length(const std::vector<Point>& points);

}  // namespace pex::planning
