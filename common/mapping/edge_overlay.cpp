#include "mapping/edge_overlay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <unordered_map>

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

bool on_same_box_side(const Point& a, const Point& b, const Box& box) {
  const auto& lo = box.min_corner();
  const auto& hi = box.max_corner();
  return (a.x() == lo.x() && b.x() == lo.x()) || (a.x() == hi.x() && b.x() == hi.x()) ||
         (a.y() == lo.y() && b.y() == lo.y()) || (a.y() == hi.y() && b.y() == hi.y());
}

class Overlay {
 public:
  Overlay(const TypedMultiPolygon& a, const TypedMultiPolygon& b) {
    add_side(a, 0);
    add_side(b, 1);
  }

  OverlayResult run(OverlayOp op, const std::optional<Box>& border_box) {
    snap_b_onto_a();
    find_splits();
    make_pieces();
    mark_coincident();
    classify(op);
    return link(border_box);
  }

 private:
  std::vector<InputEdge> edges_;
  std::vector<InputRing> rings_;
  std::vector<Split> splits_;
  std::vector<Point> vertices_;
  std::vector<std::uint8_t> vertex_sides_;  // bit s: a piece of side s starts or ends here
  // Open-addressing table of vertex ids by exact coordinates (a hash map
  // with a node per vertex cost more than the rest of the overlay).
  std::vector<std::uint32_t> vertex_table_;
  std::uint64_t vertex_mask_ = 0;
  std::vector<Piece> pieces_;

  void add_side(const TypedMultiPolygon& polygons, std::uint8_t side) {
    auto add_ring = [&](const Ring& ring, const std::vector<EdgeType>& types) {
      InputRing r{side, static_cast<std::uint32_t>(edges_.size()), 0, 0, 0, 0, 0, 0, 0};
      for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
        if (bg::equals(ring[i], ring[i + 1])) continue;
        edges_.push_back({ring[i], ring[i + 1], types[i], side, 0, 0, 0, 0});
      }
      r.last_edge = static_cast<std::uint32_t>(edges_.size());
      if (r.last_edge > r.first_edge) rings_.push_back(r);
    };
    for (const auto& polygon : polygons) {
      add_ring(polygon.geometry.outer(), polygon.edge_types[0]);
      for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
        add_ring(polygon.geometry.inners()[k], polygon.edge_types[1 + k]);
    }
  }

  // b's vertices within kEps of a vertex of a take its coordinates, so that
  // near-coincident vertices become one; b's edges that collapse are dropped.
  void snap_b_onto_a() {
    std::vector<Point> a_points;
    for (const auto& e : edges_)
      if (e.side == 0) a_points.push_back(e.p);
    std::sort(a_points.begin(), a_points.end(), [](const Point& l, const Point& r) { return l.x() < r.x(); });
    auto snap = [&](Point& p) {
      auto it = std::lower_bound(a_points.begin(), a_points.end(), p.x() - kEps,
                                 [](const Point& l, double x) { return l.x() < x; });
      for (; it != a_points.end() && it->x() <= p.x() + kEps; ++it) {
        if (std::abs(it->y() - p.y()) <= kEps && std::hypot(it->x() - p.x(), it->y() - p.y()) <= kEps) {
          p = *it;
          return;
        }
      }
    };
    std::vector<InputEdge> kept;
    kept.reserve(edges_.size());
    for (auto& ring : rings_) {
      const auto first = static_cast<std::uint32_t>(kept.size());
      for (std::uint32_t k = ring.first_edge; k < ring.last_edge; ++k) {
        InputEdge e = edges_[k];
        if (e.side == 1) {
          snap(e.p);
          snap(e.q);
          if (bg::equals(e.p, e.q)) continue;
        }
        e.min_x = std::min(e.p.x(), e.q.x());
        e.max_x = std::max(e.p.x(), e.q.x());
        e.min_y = std::min(e.p.y(), e.q.y());
        e.max_y = std::max(e.p.y(), e.q.y());
        kept.push_back(e);
      }
      ring.first_edge = first;
      ring.last_edge = static_cast<std::uint32_t>(kept.size());
      ring.min_x = ring.min_y = std::numeric_limits<double>::infinity();
      ring.max_x = ring.max_y = -std::numeric_limits<double>::infinity();
      for (std::uint32_t k = ring.first_edge; k < ring.last_edge; ++k) {
        ring.min_x = std::min(ring.min_x, kept[k].min_x);
        ring.max_x = std::max(ring.max_x, kept[k].max_x);
        ring.min_y = std::min(ring.min_y, kept[k].min_y);
        ring.max_y = std::max(ring.max_y, kept[k].max_y);
      }
    }
    edges_ = std::move(kept);
  }

  // Sweep over x: each edge meets the edges of the other side whose x and y
  // ranges overlap its own (within kEps).
  void find_splits() {
    std::vector<std::uint32_t> order(edges_.size());
    for (std::uint32_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](std::uint32_t l, std::uint32_t r) {
      return edges_[l].min_x < edges_[r].min_x || (edges_[l].min_x == edges_[r].min_x && l < r);
    });
    std::vector<std::uint32_t> active[2];
    for (const std::uint32_t k : order) {
      const InputEdge& e = edges_[k];
      auto& others = active[1 - e.side];
      for (std::size_t m = 0; m < others.size();) {
        const InputEdge& f = edges_[others[m]];
        if (f.max_x < e.min_x - kEps) {  // left behind by the sweep
          others[m] = others.back();
          others.pop_back();
          continue;
        }
        if (f.max_y >= e.min_y - kEps && f.min_y <= e.max_y + kEps) meet(edges_, k, others[m], splits_);
        ++m;
      }
      active[e.side].push_back(k);
    }
  }

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
    vertex_table_[slot] = id;
    vertices_.push_back(p);
    vertex_sides_.push_back(static_cast<std::uint8_t>(1u << side));
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
      for (std::uint32_t k = ring.first_edge; k < ring.last_edge; ++k) {
        const InputEdge& e = edges_[k];
        while (s < splits_.size() && splits_[s].edge < k) ++s;
        std::uint32_t from = vertex(e.p, e.side);
        Point last = e.p;
        for (; s < splits_.size() && splits_[s].edge == k; ++s) {
          const Point& p = splits_[s].point;
          if (bg::equals(p, last) || bg::equals(p, e.q)) continue;
          const std::uint32_t to = vertex(p, e.side);
          pieces_.push_back({from, to, e.type, e.side});
          from = to;
          last = p;
        }
        pieces_.push_back({from, vertex(e.q, e.side), e.type, e.side});
      }
      ring.last_piece = static_cast<std::uint32_t>(pieces_.size());
    }
  }

  // Pieces of a and b with the same end points: overlapping edges.
  void mark_coincident() {
    std::unordered_map<std::uint64_t, std::uint32_t> a_pieces;
    auto key = [](std::uint32_t u, std::uint32_t v) {
      return (static_cast<std::uint64_t>(std::min(u, v)) << 32) | std::max(u, v);
    };
    for (std::uint32_t k = 0; k < pieces_.size(); ++k) {
      const Piece& p = pieces_[k];
      if (p.side == 0 && (vertex_sides_[p.from] & vertex_sides_[p.to] & 2u)) a_pieces.emplace(key(p.from, p.to), k);
    }
    if (a_pieces.empty()) return;
    for (auto& p : pieces_) {
      if (p.side != 1) continue;
      const auto it = a_pieces.find(key(p.from, p.to));
      if (it == a_pieces.end()) continue;
      Piece& twin = pieces_[it->second];
      const std::int8_t how = twin.from == p.from ? 1 : -1;
      twin.coincident = p.coincident = how;
      if (how == 1) twin.type = std::min(twin.type, p.type);
    }
  }

  // Even-odd over every ring of `side` (its rings do not cross, so a point is
  // inside the multi-polygon when it is inside an odd number of them).
  bool inside(const Point& m, std::uint8_t side) const {
    bool in = false;
    for (const auto& ring : rings_) {
      if (ring.side != side || m.x() < ring.min_x || m.x() > ring.max_x || m.y() < ring.min_y ||
          m.y() > ring.max_y)
        continue;
      for (std::uint32_t k = ring.first_edge; k < ring.last_edge; ++k) {
        const Point& a = edges_[k].p;
        const Point& b = edges_[k].q;
        if ((a.y() > m.y()) != (b.y() > m.y()) &&
            m.x() < (b.x() - a.x()) * (m.y() - a.y()) / (b.y() - a.y()) + a.x())
          in = !in;
      }
    }
    return in;
  }

  // Along a ring, a piece is inside or outside the other side as the piece
  // before it, unless they meet at a vertex the other side also has: only
  // there is the midpoint test needed.
  void classify(OverlayOp op) {
    for (const auto& ring : rings_) {
      const std::uint8_t other = 1 - ring.side;
      bool known = false, in = false;
      for (std::uint32_t k = ring.first_piece; k < ring.last_piece; ++k) {
        Piece& p = pieces_[k];
        if (p.coincident != 0) {
          p.keep = p.coincident > 0 && p.side == 0;
          known = false;
          continue;
        }
        if (!known || (vertex_sides_[p.from] & (1u << other))) {
          const Point& u = vertices_[p.from];
          const Point& v = vertices_[p.to];
          in = inside(Point(0.5 * (u.x() + v.x()), 0.5 * (u.y() + v.y())), other);
          known = true;
        }
        p.keep = op == OverlayOp::kUnion ? !in : in;
      }
    }
  }

  // Links the kept pieces into rings. At a vertex with several ways on, the
  // sharpest left turn (the interior is on the left) keeps each ring to its
  // own face, so rings that touch at a point come out as separate rings.
  OverlayResult link(const std::optional<Box>& border_box) {
    OverlayResult result;
    const std::size_t nv = vertices_.size();
    std::vector<std::uint32_t> start(nv + 1, 0);
    std::size_t kept = 0;
    for (const auto& p : pieces_)
      if (p.keep) {
        ++start[p.from + 1];
        ++kept;
      }
    for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<std::uint32_t> out(kept), fill(start.begin(), start.end() - 1);
    for (std::uint32_t k = 0; k < pieces_.size(); ++k)
      if (pieces_[k].keep) out[fill[pieces_[k].from]++] = k;

    auto next_of = [&](std::uint32_t k) -> std::uint32_t {
      const std::uint32_t v = pieces_[k].to;
      const std::uint32_t b = start[v], e = start[v + 1];
      if (e == b) return kNone;
      if (e == b + 1) return out[b];
      const Point& at = vertices_[v];
      const Point& from = vertices_[pieces_[k].from];
      const double bx = from.x() - at.x(), by = from.y() - at.y();
      std::uint32_t best = kNone;
      double best_angle = -1.0;
      for (std::uint32_t m = b; m < e; ++m) {
        const Point& to = vertices_[pieces_[out[m]].to];
        const double dx = to.x() - at.x(), dy = to.y() - at.y();
        double angle = std::atan2(cross(bx, by, dx, dy), bx * dx + by * dy);
        if (angle < 0.0) angle += 2.0 * M_PI;
        if (angle > best_angle) {
          best_angle = angle;
          best = out[m];
        }
      }
      return best;
    };

    std::vector<char> used(pieces_.size(), 0);
    std::vector<TypedRing> holes;
    for (std::uint32_t first = 0; first < pieces_.size(); ++first) {
      if (!pieces_[first].keep || used[first]) continue;
      TypedRing ring;
      std::uint32_t k = first;
      for (;;) {
        used[k] = 1;
        ring.ring.push_back(vertices_[pieces_[k].from]);
        ring.types.push_back(pieces_[k].type);
        const std::uint32_t next = next_of(k);
        if (next == first) break;
        if (next == kNone || used[next]) {
          result.error = "overlay: pieces do not link into rings";
          return result;
        }
        k = next;
      }
      ring.ring.push_back(ring.ring.front());
      if (border_box) {
        for (std::size_t i = 0; i + 1 < ring.ring.size(); ++i)
          if (on_same_box_side(ring.ring[i], ring.ring[i + 1], *border_box)) ring.types[i] = EdgeType::kBorder;
      }
      const double a = bg::area(ring.ring);
      if (ring.types.size() < 3 || a == 0.0) {
        result.error = "overlay: a degenerate ring";
        return result;
      }
      if (a > 0.0) {
        TypedPolygon polygon;
        polygon.geometry.outer() = std::move(ring.ring);
        polygon.edge_types.push_back(std::move(ring.types));
        result.polygons.push_back(std::move(polygon));
      } else {
        holes.push_back(std::move(ring));
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

OverlayResult overlay(const TypedMultiPolygon& a, const TypedMultiPolygon& b, OverlayOp op,
                      const std::optional<Box>& border_box) {
  return Overlay(a, b).run(op, border_box);
}

}  // namespace pex::mapping
