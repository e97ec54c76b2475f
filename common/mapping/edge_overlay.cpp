#include "mapping/edge_overlay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "mapping/typed_ops.hpp"

namespace pex::mapping {

namespace {

constexpr double kEps = kOverlaySnap;
constexpr std::uint32_t kNone = 0xffffffffu;

struct InputEdge {
  Point p, q;
  EdgeType type;
  std::uint8_t side;
  double min_x, max_x, min_y, max_y;
};

struct InputRing {
  std::uint8_t side;
  std::uint32_t first_edge, last_edge;  // [first, last) in edges
  std::uint32_t first_piece = 0, last_piece = 0;
  double min_x, max_x, min_y, max_y;
};

// A point where an edge is to be split, at parameter t along it.
struct Split {
  std::uint32_t edge;
  double t;
  Point point;
};

// A piece of an input edge between consecutive split points.
struct Piece {
  std::uint32_t from, to;  // vertex ids
  EdgeType type;
  std::uint8_t side;
  std::int8_t coincident = 0;  // +1: the other side has it in the same direction, -1: opposite
  bool keep = false;
};

double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// A stand-in for the counter-clockwise angle from (ax, ay) to (bx, by) in
// [0, 4): monotone in the true angle in [0, 2 pi) (only order matters to the
// callers), 0 for the same direction, without atan2.
double turn_order(double ax, double ay, double bx, double by) {
  const double c = cross(ax, ay, bx, by), d = ax * bx + ay * by;
  if (c == 0.0 && d > 0.0) return 0.0;
  // Diamond angle of the direction (d, c) in the frame of a.
  const double r = c / (std::abs(d) + std::abs(c));
  if (d >= 0.0) return c >= 0.0 ? r : 4.0 + r;  // [0, 1) or (3, 4)
  return 2.0 - r;                                // (1, 3]
}

// True if p lies on the edge's interior: within kEps of it and more than
// kEps from both ends; t is its parameter.
bool on_interior(const Point& p, const InputEdge& e, double& t) {
  const double dx = e.q.x() - e.p.x(), dy = e.q.y() - e.p.y();
  const double wx = p.x() - e.p.x(), wy = p.y() - e.p.y();
  const double len2 = dx * dx + dy * dy;
  const double dot = wx * dx + wy * dy;
  if (dot <= 0.0 || dot >= len2) return false;
  const double c = cross(dx, dy, wx, wy);
  if (c * c > kEps * kEps * len2) return false;
  const double len = std::sqrt(len2);
  t = dot / len2;
  return t * len > kEps && (1.0 - t) * len > kEps;
}

// Records where edges i and j (of different sides) meet: an end point of one
// on the other splits the other there; a proper crossing splits both at the
// same computed point.
void meet(const std::vector<InputEdge>& edges, std::uint32_t i, std::uint32_t j, std::vector<Split>& splits) {
  const InputEdge& e = edges[i];
  const InputEdge& f = edges[j];
  bool touched = false;
  auto end_on = [&](const Point& p, std::uint32_t k) {
    const InputEdge& g = edges[k];
    if (bg::equals(p, g.p) || bg::equals(p, g.q)) {
      touched = true;
      return;
    }
    double t = 0.0;
    if (on_interior(p, g, t)) {
      splits.push_back({k, t, p});
      touched = true;
    }
  };
  end_on(f.p, i);
  end_on(f.q, i);
  end_on(e.p, j);
  end_on(e.q, j);
  if (touched) return;
  const double ex = e.q.x() - e.p.x(), ey = e.q.y() - e.p.y();
  const double fx = f.q.x() - f.p.x(), fy = f.q.y() - f.p.y();
  const double d1 = cross(ex, ey, f.p.x() - e.p.x(), f.p.y() - e.p.y());
  const double d2 = cross(ex, ey, f.q.x() - e.p.x(), f.q.y() - e.p.y());
  if (!((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))) return;
  const double d3 = cross(fx, fy, e.p.x() - f.p.x(), e.p.y() - f.p.y());
  const double d4 = cross(fx, fy, e.q.x() - f.p.x(), e.q.y() - f.p.y());
  if (!((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))) return;
  const double te = d3 / (d3 - d4), tf = d1 / (d1 - d2);
  const Point x(e.p.x() + te * ex, e.p.y() + te * ey);
  splits.push_back({i, te, x});
  splits.push_back({j, tf, x});
}

std::uint64_t hash_of(double x, double y) {
  x += 0.0;  // -0.0 and 0.0 are one vertex
  y += 0.0;
  std::uint64_t bx, by;
  std::memcpy(&bx, &x, sizeof x);
  std::memcpy(&by, &y, sizeof y);
  std::uint64_t h = bx * 0x9E3779B97F4A7C15ull ^ (by + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
  return h ^ (h >> 29);
}

// Lists items by key (compressed rows): items of key k are
// items[start[k] .. start[k + 1]). for_each(emit) calls emit(key, item) for
// every pair; it runs twice, to count and then to fill. `fill` is scratch.
template <class ForEach>
void build_lists(std::size_t keys, std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& items,
                 std::vector<std::uint32_t>& fill, ForEach&& for_each) {
  start.assign(keys + 1, 0);
  for_each([&](std::size_t key, std::uint32_t) { ++start[key + 1]; });
  for (std::size_t k = 0; k < keys; ++k) start[k + 1] += start[k];
  items.resize(start.back());
  fill.assign(start.begin(), start.end() - 1);
  for_each([&](std::size_t key, std::uint32_t item) { items[fill[key]++] = item; });
}

// The working state of one overlay. Its buffers keep their capacity from
// call to call (one per thread, see overlay()): allocation was a fifth of the
// cost of small overlays.
class Overlay {
 public:
  OverlayResult run(std::span<const RingRef> a, std::span<const RingRef> b, OverlayOp op,
                    const std::optional<Box>& border_box, const std::optional<EdgeType> (&side_types)[2]) {
    clear();
    add_side(a, 0, side_types[0]);
    sort_a_points(b);
    add_side(b, 1, side_types[1]);
    set_meet_box();
    find_splits();
    make_pieces();
    index_incidence();
    mark_coincident();
    classify(op);
    return link(border_box);
  }

 private:
  std::vector<InputEdge> edges_;
  std::vector<InputRing> rings_;
  std::vector<Point> a_points_;  // a's vertices by x, for snapping b's
  std::vector<Split> splits_;
  std::vector<std::uint32_t> cell_start_, cell_edges_;  // b's edges by grid cell
  std::vector<std::uint32_t> tested_by_;                // by edge of b: the edge of a that last met it
  std::vector<Point> vertices_;
  std::vector<std::uint8_t> vertex_sides_;  // bit s: a piece of side s starts or ends here
  // Open-addressing table of vertex ids by exact coordinates (a hash map
  // with a node per vertex cost more than the rest of the overlay).
  std::vector<std::uint32_t> vertex_table_;
  std::uint64_t vertex_mask_ = 0;
  std::vector<Piece> pieces_;
  std::vector<std::uint32_t> incident_start_, incident_;  // pieces by vertex (either end)
  std::vector<std::uint32_t> out_start_, out_;  // kept pieces by start vertex
  std::vector<std::uint32_t> fill_;             // scratch of build_lists
  std::vector<char> used_;
  std::vector<std::uint32_t> ring_pieces_;  // the ring being linked
  std::vector<std::uint32_t> loop_;         // its pieces not yet emitted as a loop
  std::vector<std::int32_t> position_;      // a vertex's place in loop_, -1 if none
  struct Slabs {
    bool built = false;
    double min_y = 0, max_y = 0, height = 1;
    std::vector<std::uint32_t> start, edges;  // edges by row
  };
  Slabs slabs_[2];
  // Where the sides can meet: the overlap of their boxes, widened by kEps.
  // Edges and vertices outside it meet nothing of the other side.
  double meet_min_x_ = 0, meet_max_x_ = -1, meet_min_y_ = 0, meet_max_y_ = -1;

  void set_meet_box() {
    double box[2][4];
    for (auto& b : box) b[0] = b[2] = std::numeric_limits<double>::infinity(), b[1] = b[3] = -b[0];
    for (const auto& r : rings_) {
      double* b = box[r.side];
      b[0] = std::min(b[0], r.min_x);
      b[1] = std::max(b[1], r.max_x);
      b[2] = std::min(b[2], r.min_y);
      b[3] = std::max(b[3], r.max_y);
    }
    meet_min_x_ = std::max(box[0][0], box[1][0]) - kEps;
    meet_max_x_ = std::min(box[0][1], box[1][1]) + kEps;
    meet_min_y_ = std::max(box[0][2], box[1][2]) - kEps;
    meet_max_y_ = std::min(box[0][3], box[1][3]) + kEps;
  }
  bool near_meet_box(const InputEdge& e) const {
    return e.max_x >= meet_min_x_ && e.min_x <= meet_max_x_ && e.max_y >= meet_min_y_ && e.min_y <= meet_max_y_;
  }

  void clear() {
    slabs_[0].built = slabs_[1].built = false;
    edges_.clear();
    rings_.clear();
    a_points_.clear();
    splits_.clear();
    vertices_.clear();
    vertex_sides_.clear();
    pieces_.clear();
  }

  void add_side(std::span<const RingRef> rings, std::uint8_t side, std::optional<EdgeType> type) {
    for (const RingRef& ref : rings) {
      const Ring& ring = *ref.ring;
      const std::vector<EdgeType>& types = *ref.types;
      if (ring.size() < 2) continue;
      InputRing r{side, static_cast<std::uint32_t>(edges_.size()), 0, 0, 0, 0, 0, 0, 0};
      r.min_x = r.min_y = std::numeric_limits<double>::infinity();
      r.max_x = r.max_y = -std::numeric_limits<double>::infinity();
      Point p = snapped(ring.front(), side);
      for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        const Point q = snapped(ring[i + 1], side);
        if (bg::equals(p, q)) continue;  // repeated, or b's edge collapsed by snapping
        InputEdge e{p, q, type.value_or(types[i]), side, std::min(p.x(), q.x()), std::max(p.x(), q.x()),
                    std::min(p.y(), q.y()), std::max(p.y(), q.y())};
        r.min_x = std::min(r.min_x, e.min_x);
        r.max_x = std::max(r.max_x, e.max_x);
        r.min_y = std::min(r.min_y, e.min_y);
        r.max_y = std::max(r.max_y, e.max_y);
        edges_.push_back(e);
        p = q;
      }
      r.last_edge = static_cast<std::uint32_t>(edges_.size());
      if (r.last_edge > r.first_edge) rings_.push_back(r);
    }
  }

  // Only a's vertices within kEps of b's box can take a vertex of b.
  void sort_a_points(std::span<const RingRef> b) {
    double min_x = std::numeric_limits<double>::infinity(), max_x = -min_x, min_y = min_x, max_y = -min_x;
    for (const RingRef& ref : b)
      for (const Point& p : *ref.ring) {
        min_x = std::min(min_x, p.x()), max_x = std::max(max_x, p.x());
        min_y = std::min(min_y, p.y()), max_y = std::max(max_y, p.y());
      }
    for (const auto& e : edges_)
      if (e.p.x() >= min_x - kEps && e.p.x() <= max_x + kEps && e.p.y() >= min_y - kEps && e.p.y() <= max_y + kEps)
        a_points_.push_back(e.p);
    std::sort(a_points_.begin(), a_points_.end(), [](const Point& l, const Point& r) { return l.x() < r.x(); });
  }

  // b's vertices within kEps of a vertex of a take its coordinates, so that
  // near-coincident vertices become one.
  Point snapped(const Point& p, std::uint8_t side) const {
    if (side == 0) return p;
    auto it = std::lower_bound(a_points_.begin(), a_points_.end(), p.x() - kEps,
                               [](const Point& l, double x) { return l.x() < x; });
    for (; it != a_points_.end() && it->x() <= p.x() + kEps; ++it)
      if (std::abs(it->y() - p.y()) <= kEps && std::hypot(it->x() - p.x(), it->y() - p.y()) <= kEps) return *it;
    return p;
  }

  // Each edge of a meets the edges of b that come within kEps of it, found
  // through a uniform grid over the region where the sides can meet: b's
  // edges are listed in the cells their kEps-wide band crosses (not every
  // cell of their box: a long diagonal frontier edge of a scan covers many
  // more cells than it crosses), each edge of a visits the cells its band
  // crosses, and a pair met in several cells is tested once (tested_by_).
  void find_splits() {
    if (meet_max_x_ < meet_min_x_ || meet_max_y_ < meet_min_y_) return;
    const double min_x = meet_min_x_, max_x = meet_max_x_, min_y = meet_min_y_, max_y = meet_max_y_;
    const int n = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(edges_.size()) / 4.0)), 1, 64);
    const double cell_x = std::max((max_x - min_x) / n, 1e-6), cell_y = std::max((max_y - min_y) / n, 1e-6);
    // Clamped in double before the cast: a far coordinate does not fit an int.
    const double last = n - 1;
    auto col = [&](double x) { return static_cast<int>(std::clamp((x - min_x) / cell_x, 0.0, last)); };
    auto row = [&](double y) { return static_cast<int>(std::clamp((y - min_y) / cell_y, 0.0, last)); };
    // fn(cell) for every cell the edge's band (the points within kEps of it)
    // can reach: row by row, the columns of the part of the edge inside the
    // row's slab widened by kEps, widened by kEps. The outer rows and
    // columns reach to infinity (col and row clamp).
    auto for_each_cell = [&](const InputEdge& e, auto&& fn) {
      const int first_row = row(e.min_y - kEps), last_row = row(e.max_y + kEps);
      const double dx = e.q.x() - e.p.x(), dy = e.q.y() - e.p.y();
      for (int r = first_row; r <= last_row; ++r) {
        int c0 = col(e.min_x - kEps), c1 = col(e.max_x + kEps);
        if (first_row != last_row && dy != 0.0) {
          const double slab_lo = r == 0 ? e.min_y : std::max(e.min_y, min_y + r * cell_y - kEps);
          const double slab_hi = r == n - 1 ? e.max_y : std::min(e.max_y, min_y + (r + 1) * cell_y + kEps);
          // Parameters clamped to the edge: finite even when dy is so small
          // that a slope would overflow.
          const double ta = std::clamp((slab_lo - e.p.y()) / dy, 0.0, 1.0);
          const double tb = std::clamp((slab_hi - e.p.y()) / dy, 0.0, 1.0);
          const double xa = e.p.x() + ta * dx, xb = e.p.x() + tb * dx;
          c0 = std::max(c0, col(std::min(xa, xb) - kEps));
          c1 = std::min(c1, col(std::max(xa, xb) + kEps));
        }
        for (int c = c0; c <= c1; ++c) fn(static_cast<std::size_t>(r * n + c));
      }
    };
    build_lists(static_cast<std::size_t>(n * n), cell_start_, cell_edges_, fill_, [&](auto&& emit) {
      for (std::uint32_t k = 0; k < edges_.size(); ++k) {
        const InputEdge& e = edges_[k];
        if (e.side == 1 && near_meet_box(e)) for_each_cell(e, [&](std::size_t cell) { emit(cell, k); });
      }
    });
    tested_by_.assign(edges_.size(), kNone);
    for (std::uint32_t k = 0; k < edges_.size(); ++k) {
      const InputEdge& e = edges_[k];
      if (e.side != 0 || !near_meet_box(e)) continue;
      for_each_cell(e, [&](std::size_t cell) {
        for (std::uint32_t m = cell_start_[cell]; m < cell_start_[cell + 1]; ++m) {
          const std::uint32_t j = cell_edges_[m];
          if (tested_by_[j] == k) continue;  // met in an earlier cell
          tested_by_[j] = k;
          const InputEdge& f = edges_[j];
          if (f.max_x < e.min_x - kEps || f.min_x > e.max_x + kEps || f.max_y < e.min_y - kEps ||
              f.min_y > e.max_y + kEps)
            continue;
          meet(edges_, k, j, splits_);
        }
      });
    }
  }

  // The id of the vertex at p: one id for one point, also where an operand
  // touches itself (two of its rings at one point: a union can join them
  // into one ring, which must then split there). Ring neighbours pass their
  // ids along (make_pieces).
  std::uint32_t vertex(const Point& p, std::uint8_t side) {
    std::uint64_t slot = hash_of(p.x(), p.y()) & vertex_mask_;
    for (;; slot = (slot + 1) & vertex_mask_) {
      const std::uint32_t id = vertex_table_[slot];
      if (id == kNone) break;
      if (vertices_[id].x() == p.x() && vertices_[id].y() == p.y()) {
        vertex_sides_[id] |= static_cast<std::uint8_t>(1u << side);
        return id;
      }
    }
    const auto id = static_cast<std::uint32_t>(vertices_.size());
    vertices_.push_back(p);
    vertex_sides_.push_back(static_cast<std::uint8_t>(1u << side));
    vertex_table_[slot] = id;
    return id;
  }

  void make_pieces() {
    std::sort(splits_.begin(), splits_.end(), [](const Split& l, const Split& r) {
      return l.edge < r.edge || (l.edge == r.edge && l.t < r.t);
    });
    std::size_t slots = 16;
    while (slots < 2 * (edges_.size() + splits_.size())) slots *= 2;
    vertex_table_.assign(slots, kNone);
    vertex_mask_ = slots - 1;
    vertices_.reserve(edges_.size() + splits_.size());
    vertex_sides_.reserve(edges_.size() + splits_.size());
    pieces_.reserve(edges_.size() + splits_.size());
    std::size_t s = 0;
    for (auto& ring : rings_) {
      ring.first_piece = static_cast<std::uint32_t>(pieces_.size());
      const std::uint32_t ring_start = vertex(edges_[ring.first_edge].p, ring.side);
      std::uint32_t from = ring_start;
      for (std::uint32_t k = ring.first_edge; k < ring.last_edge; ++k) {
        const InputEdge& e = edges_[k];
        while (s < splits_.size() && splits_[s].edge < k) ++s;
        Point last = e.p;
        for (; s < splits_.size() && splits_[s].edge == k; ++s) {
          const Point& p = splits_[s].point;
          if (bg::equals(p, last) || bg::equals(p, e.q)) continue;
          const std::uint32_t to = vertex(p, e.side);
          pieces_.push_back({from, to, e.type, e.side});
          from = to;
          last = p;
        }
        // The ring's edges are consecutive and closed: e.q starts the next.
        const std::uint32_t to = k + 1 < ring.last_edge ? vertex(e.q, e.side) : ring_start;
        pieces_.push_back({from, to, e.type, e.side});
        from = to;
      }
      ring.last_piece = static_cast<std::uint32_t>(pieces_.size());
    }
  }

  // For each vertex, the pieces that start or end there.
  void index_incidence() {
    build_lists(vertices_.size(), incident_start_, incident_, fill_, [&](auto&& emit) {
      for (std::uint32_t k = 0; k < pieces_.size(); ++k) {
        emit(pieces_[k].from, k);
        emit(pieces_[k].to, k);
      }
    });
  }

  // Pieces of a and b with the same end points: overlapping edges.
  void mark_coincident() {
    for (auto& p : pieces_) {
      if (p.side != 1 || !(vertex_sides_[p.from] & vertex_sides_[p.to] & 1u)) continue;
      for (std::uint32_t m = incident_start_[p.from]; m < incident_start_[p.from + 1]; ++m) {
        Piece& twin = pieces_[incident_[m]];
        if (twin.side != 0) continue;
        const bool same = twin.from == p.from && twin.to == p.to;
        if (!same && !(twin.from == p.to && twin.to == p.from)) continue;
        twin.coincident = p.coincident = same ? 1 : -1;
        twin.type = std::min(twin.type, p.type);  // used if a's piece is kept
        break;
      }
    }
  }

  // Even-odd over every ring of `side` (its rings do not cross, so a point is
  // inside the multi-polygon when it is inside an odd number of them).
  // The edges are listed by horizontal slab (built on the first test of a
  // side), so a test reads only the edges of its slab: rings that meet the
  // other side nowhere take one test each, and merging a whole map has
  // hundreds of them against thousands of edges.
  bool inside(const Point& m, std::uint8_t side) {
    Slabs& slabs = slabs_[side];
    if (!slabs.built) build_slabs(side);
    if (slabs.start.empty() || m.y() < slabs.min_y || m.y() > slabs.max_y) return false;
    const auto rows = static_cast<int>(slabs.start.size() - 1);
    const int row = std::clamp(static_cast<int>((m.y() - slabs.min_y) / slabs.height), 0, rows - 1);
    bool in = false;
    for (std::uint32_t j = slabs.start[static_cast<std::size_t>(row)]; j < slabs.start[static_cast<std::size_t>(row) + 1];
         ++j) {
      const InputEdge& e = edges_[slabs.edges[j]];
      if (ray_crosses(m, e.p, e.q)) in = !in;
    }
    return in;
  }

  void build_slabs(std::uint8_t side) {
    Slabs& slabs = slabs_[side];
    slabs.built = true;
    slabs.start.clear();
    slabs.edges.clear();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::size_t count = 0;
    for (const auto& e : edges_)
      if (e.side == side) {
        lo = std::min(lo, e.min_y);
        hi = std::max(hi, e.max_y);
        ++count;
      }
    if (count == 0) return;
    const int rows = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(count))), 1, 256);
    slabs.min_y = lo;
    slabs.max_y = hi;
    slabs.height = std::max((hi - lo) / rows, 1e-9);
    auto row = [&](double y) { return std::clamp(static_cast<int>((y - lo) / slabs.height), 0, rows - 1); };
    build_lists(static_cast<std::size_t>(rows), slabs.start, slabs.edges, fill_, [&](auto&& emit) {
      for (std::uint32_t k = 0; k < edges_.size(); ++k)
        if (edges_[k].side == side)
          for (int r = row(edges_[k].min_y); r <= row(edges_[k].max_y); ++r) emit(static_cast<std::size_t>(r), k);
    });
  }

  // Whether piece p, leaving a vertex the other side's boundary passes
  // through, enters the other side, read off the other side's pieces at that
  // vertex: the other side's interior is on the left of its pieces, so what
  // lies just counter-clockwise of a piece leaving the vertex is inside and
  // what lies just counter-clockwise of a piece arriving is outside. The
  // first of them clockwise from p decides. nullopt: a piece of the other
  // side has p's direction (a degenerate meeting the caller resolves with a
  // point-in-polygon test).
  std::optional<bool> enters_other_side(const Piece& p) const {
    const std::uint32_t v = p.from;
    const Point& at = vertices_[v];
    const Point& to = vertices_[p.to];
    const double dx = to.x() - at.x(), dy = to.y() - at.y();
    double best = 10.0;
    bool best_leaves = false;
    for (std::uint32_t m = incident_start_[v]; m < incident_start_[v + 1]; ++m) {
      const Piece& q = pieces_[incident_[m]];
      if (q.side == p.side) continue;
      const bool leaves = q.from == v;
      const Point& w = vertices_[leaves ? q.to : q.from];
      const double ex = w.x() - at.x(), ey = w.y() - at.y();
      const double angle = turn_order(ex, ey, dx, dy);  // from q's direction to p's, ccw
      if (angle == 0.0) return std::nullopt;
      if (angle < best) {
        best = angle;
        best_leaves = leaves;
      }
    }
    if (best > 4.0) return std::nullopt;
    return best_leaves;
  }

  // Along a ring, a piece is inside or outside the other side as the piece
  // before it, unless they meet at a vertex the other side's boundary passes
  // through: there the pieces around the vertex decide. A ring that meets
  // the other side nowhere is inside or outside as a whole (one
  // point-in-polygon test).
  void classify(OverlayOp op) {
    for (const auto& ring : rings_) {
      const std::uint8_t other = 1 - ring.side;
      const std::uint32_t n = ring.last_piece - ring.first_piece;
      std::uint32_t first = 0;
      while (first < n && !(vertex_sides_[pieces_[ring.first_piece + first].from] & (1u << other))) ++first;
      if (first == n) first = 0;
      bool known = false, in = false;
      for (std::uint32_t j = 0; j < n; ++j) {
        Piece& p = pieces_[ring.first_piece + (first + j) % n];
        if (p.coincident != 0) {
          // One copy (a's) where the piece bounds the result: same direction
          // for union and intersection, opposite for the difference.
          p.keep = p.side == 0 && (p.coincident > 0) == (op != OverlayOp::kDifference);
          known = false;
          continue;
        }
        if (!known || (vertex_sides_[p.from] & (1u << other))) {
          std::optional<bool> enters;
          if (vertex_sides_[p.from] & (1u << other)) enters = enters_other_side(p);
          if (!enters) {
            const Point& u = vertices_[p.from];
            const Point& v = vertices_[p.to];
            enters = inside(Point(0.5 * (u.x() + v.x()), 0.5 * (u.y() + v.y())), other);
          }
          in = *enters;
          known = true;
        }
        switch (op) {
          case OverlayOp::kUnion: p.keep = !in; break;
          case OverlayOp::kIntersection: p.keep = in; break;
          case OverlayOp::kDifference: p.keep = p.side == 0 ? !in : in; break;
        }
      }
    }
    // a minus b: b's pieces inside a bound the result with a's interior on
    // their right; turned round, the result is on their left as everywhere.
    if (op == OverlayOp::kDifference)
      for (auto& p : pieces_)
        if (p.keep && p.side == 1) std::swap(p.from, p.to);
  }

  // Links the kept pieces into rings. At a vertex with several ways on, the
  // sharpest left turn (the interior is on the left) keeps each ring to its
  // own face, so rings that touch at a point come out as separate rings.
  OverlayResult link(const std::optional<Box>& border_box) {
    OverlayResult result;
    const std::size_t nv = vertices_.size();
    build_lists(nv, out_start_, out_, fill_, [&](auto&& emit) {
      for (std::uint32_t k = 0; k < pieces_.size(); ++k)
        if (pieces_[k].keep) emit(pieces_[k].from, k);
    });

    auto next_of = [&](std::uint32_t k) -> std::uint32_t {
      const std::uint32_t v = pieces_[k].to;
      const std::uint32_t b = out_start_[v], e = out_start_[v + 1];
      if (e == b) return kNone;
      if (e == b + 1) return out_[b];
      const Point& at = vertices_[v];
      const Point& from = vertices_[pieces_[k].from];
      const double bx = from.x() - at.x(), by = from.y() - at.y();
      std::uint32_t best = kNone;
      double best_angle = -1.0;
      for (std::uint32_t m = b; m < e; ++m) {
        const Point& to = vertices_[pieces_[out_[m]].to];
        const double dx = to.x() - at.x(), dy = to.y() - at.y();
        const double angle = turn_order(bx, by, dx, dy);
        if (angle > best_angle) {
          best_angle = angle;
          best = out_[m];
        }
      }
      return best;
    };

    used_.assign(pieces_.size(), 0);
    position_.assign(nv, -1);
    std::vector<TypedRing> holes;
    // One closed loop of pieces: a polygon (counter-clockwise) or a hole.
    auto emit = [&](std::span<const std::uint32_t> loop) {
      TypedRing ring;
      ring.ring.reserve(loop.size() + 1);
      ring.types.reserve(loop.size());
      for (const std::uint32_t piece : loop) {
        ring.ring.push_back(vertices_[pieces_[piece].from]);
        ring.types.push_back(pieces_[piece].type);
      }
      ring.ring.push_back(ring.ring.front());
      if (border_box) {
        for (std::size_t i = 0; i + 1 < ring.ring.size(); ++i)
          if (on_same_box_side(ring.ring[i], ring.ring[i + 1], *border_box)) ring.types[i] = EdgeType::kBorder;
      }
      const double a = bg::area(ring.ring);
      if (ring.types.size() < 3 || a == 0.0) return false;
      if (a > 0.0) {
        TypedPolygon polygon;
        polygon.geometry.outer() = std::move(ring.ring);
        polygon.edge_types.push_back(std::move(ring.types));
        result.polygons.push_back(std::move(polygon));
      } else {
        holes.push_back(std::move(ring));
      }
      return true;
    };
    for (std::uint32_t first = 0; first < pieces_.size(); ++first) {
      if (!pieces_[first].keep || used_[first]) continue;
      ring_pieces_.clear();
      std::uint32_t k = first;
      for (;;) {
        used_[k] = 1;
        ring_pieces_.push_back(k);
        const std::uint32_t next = next_of(k);
        if (next == first) break;
        if (next == kNone || used_[next]) {
          result.error = "overlay: pieces do not link into rings";
          return result;
        }
        k = next;
      }
      // The sharpest left turn keeps polygons that touch at a point apart, but
      // joins holes that touch at a point (and a hole touching its outer
      // ring) into one ring through that point twice, which OGC forbids: such
      // a ring is cut into its loops at every repeated vertex.
      loop_.clear();
      bool degenerate = false;
      for (const std::uint32_t piece : ring_pieces_) {
        const std::uint32_t v = pieces_[piece].from;
        if (position_[v] >= 0) {
          const auto at = static_cast<std::size_t>(position_[v]);
          degenerate |= !emit(std::span(loop_).subspan(at));
          for (std::size_t j = at; j < loop_.size(); ++j) position_[pieces_[loop_[j]].from] = -1;
          loop_.resize(at);
        }
        position_[v] = static_cast<std::int32_t>(loop_.size());
        loop_.push_back(piece);
      }
      degenerate |= !emit(loop_);
      for (const std::uint32_t piece : loop_) position_[pieces_[piece].from] = -1;
      if (degenerate) {
        result.error = "overlay: a degenerate ring";
        return result;
      }
    }
    if (!put_back_holes(result.polygons, std::move(holes))) {
      result.error = "overlay: a hole with no polygon around it";
      result.polygons.clear();
      return result;
    }
    result.ok = true;
    return result;
  }
};

}  // namespace

void add_rings(const TypedPolygon& polygon, std::vector<RingRef>& rings) {
  rings.push_back({&polygon.geometry.outer(), &polygon.edge_types[0]});
  for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
    rings.push_back({&polygon.geometry.inners()[k], &polygon.edge_types[1 + k]});
}

void add_rings(const TypedMultiPolygon& polygons, std::vector<RingRef>& rings) {
  for (const auto& polygon : polygons) add_rings(polygon, rings);
}

OverlayResult overlay(std::span<const RingRef> a, std::span<const RingRef> b, OverlayOp op,
                      const std::optional<Box>& border_box, const std::optional<EdgeType> (&side_types)[2]) {
  thread_local Overlay workspace;
  return workspace.run(a, b, op, border_box, side_types);
}

OverlayResult overlay(const TypedMultiPolygon& a, const TypedMultiPolygon& b, OverlayOp op,
                      const std::optional<Box>& border_box) {
  std::vector<RingRef> a_rings, b_rings;
  add_rings(a, a_rings);
  add_rings(b, b_rings);
  return overlay(a_rings, b_rings, op, border_box);
}

}  // namespace pex::mapping
