#include "mapping/tile_grid.hpp"

#include <algorithm>
#include <array>
#include <optional>
#include <cmath>
#include <vector>

namespace pex::mapping {

namespace {

// A crossing within this of a grid line is put on it, and one within this of
// an end point or of the previous crossing is dropped.
constexpr double kGridSnap = 1e-9;

// Points where segment p-q crosses grid lines, ordered from p to q.
void grid_crossings(const Point& p, const Point& q, const TileGrid& grid, std::vector<Point>& out) {
  out.clear();
  // Most edges lie well within one tile: no line within kClearOfLinesM of
  // their box (far more than line()'s rounding onto the overlay's grid
  // moves a line), decided without line()'s rounding.
  constexpr double kClearOfLinesM = 1e-5;
  auto clear_of_lines = [&](double lo, double hi) {
    const double line_below = grid.origin_m + std::floor((lo - grid.origin_m) / grid.size_m) * grid.size_m;
    return lo - line_below > kClearOfLinesM && line_below + grid.size_m - hi > kClearOfLinesM;
  };
  if (clear_of_lines(std::min(p.x(), q.x()), std::max(p.x(), q.x())) &&
      clear_of_lines(std::min(p.y(), q.y()), std::max(p.y(), q.y())))
    return;
  // Canonical order, so both traversal directions compute the same bits.
  const bool swap = (q.x() < p.x()) || (q.x() == p.x() && q.y() < p.y());
  const Point a = swap ? q : p, b = swap ? p : q;
  std::vector<std::pair<double, Point>> hits;
  auto snap = [&](double v) {
    const double g = grid.line(static_cast<std::int64_t>(std::round((v - grid.origin_m) / grid.size_m)));
    return std::abs(v - g) <= kGridSnap ? g : v;
  };
  if (a.x() != b.x()) {
    for (std::int64_t k = grid.index(a.x()); grid.line(k) < b.x(); ++k) {
      const double x = grid.line(k);
      if (x <= a.x()) continue;
      const double t = (x - a.x()) / (b.x() - a.x());
      hits.push_back({t, Point(x, snap(a.y() + t * (b.y() - a.y())))});
    }
  }
  const double ylo = std::min(a.y(), b.y()), yhi = std::max(a.y(), b.y());
  if (ylo != yhi) {
    for (std::int64_t k = grid.index(ylo); grid.line(k) < yhi; ++k) {
      const double y = grid.line(k);
      if (y <= ylo) continue;
      const double t = (y - a.y()) / (b.y() - a.y());
      hits.push_back({t, Point(snap(a.x() + t * (b.x() - a.x())), y)});
    }
  }
  std::sort(hits.begin(), hits.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  for (const auto& h : hits) {
    if (!out.empty() && bg::distance(out.back(), h.second) < kGridSnap) continue;
    if (bg::distance(h.second, a) < kGridSnap || bg::distance(h.second, b) < kGridSnap) continue;
    out.push_back(h.second);
  }
  if (swap) std::reverse(out.begin(), out.end());
}

// Splits ring's edges at grid lines; `types`, if given, is split alongside
// (each piece keeps its edge's type).
void split_ring(Ring& ring, std::vector<EdgeType>* types, const TileGrid& grid) {
  if (ring.size() < 2) return;
  Ring out;
  out.reserve(ring.size());
  std::vector<EdgeType> out_types;
  if (types) out_types.reserve(types->size());
  std::vector<Point> crossings;
  for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
    out.push_back(ring[i]);
    grid_crossings(ring[i], ring[i + 1], grid, crossings);
    out.insert(out.end(), crossings.begin(), crossings.end());
    if (types) out_types.insert(out_types.end(), 1 + crossings.size(), (*types)[i]);
  }
  out.push_back(ring.back());
  ring = std::move(out);
  if (types) *types = std::move(out_types);
}

// A point of a box's boundary in counter-clockwise order from the lower
// left corner: the side (0 bottom, 1 right, 2 top, 3 left; a corner belongs
// to the side it starts) and the position along it, growing
// counter-clockwise. Compared exactly, as the coordinates are.
struct SidePosition {
  int side = 0;
  double along = 0.0;
  auto operator<=>(const SidePosition&) const = default;
};

// clip_split_to_tile's walk (see tile_grid.hpp). Each edge is inside the box
// (its interior in the box's interior), on a side with the polygon's inside
// towards the box (kept, typed kBorder), or outside; the maximal runs of
// kept edges of a ring that is not kept whole start and end on the sides,
// and each run's end is joined to the next run's start counter-clockwise
// along the sides: the polygon's inside is on the left of its edges and of
// a counter-clockwise walk round the box alike.
class TileClipper {
 public:
  void set_box(const Box& box) {
    x0_ = box.min_corner().x(), y0_ = box.min_corner().y(), x1_ = box.max_corner().x(), y1_ = box.max_corner().y();
    corners_ = {Point(x0_, y0_), Point(x1_, y0_), Point(x1_, y1_), Point(x0_, y1_)};
  }

  bool clip(const TypedPolygon& polygon, TypedMultiPolygon& out) {
    const std::size_t rings = 1 + polygon.geometry.inners().size();
    if (polygon.edge_types.size() != rings) return false;
    chains_.clear();
    on_sides_.clear();
    bool outer_whole = false;
    whole_holes_.clear();
    open_rings_.clear();
    const auto ring_of = [&](std::size_t r) -> const Ring& {
      return r == 0 ? polygon.geometry.outer() : polygon.geometry.inners()[r - 1];
    };
    for (std::size_t r = 0; r < rings; ++r) {
      const Ring& ring = ring_of(r);
      if (ring.size() < 4) return false;
      const std::size_t n = ring.size() - 1;
      kinds_.resize(n);
      std::size_t kept = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if (near_sides(ring[i])) return false;
        if (on_side(ring[i])) on_sides_.push_back(ring[i]);
        const auto kind = classify(ring[i], ring[i + 1]);
        if (!kind) return false;
        kinds_[i] = *kind;
        kept += *kind != Kind::kOut ? 1 : 0;
      }
      if (kept == n) {
        if (r == 0) outer_whole = true;
        else whole_holes_.push_back(r);
        continue;
      }
      if (kept == 0) {
        open_rings_.push_back(r);
        continue;
      }
      // Runs of kept edges, each from the edge after an outside one.
      for (std::size_t i = 0; i < n; ++i) {
        if (kinds_[i] == Kind::kOut || kinds_[(i + n - 1) % n] != Kind::kOut) continue;
        Chain chain{r, i, 0, {}, {}, {}};
        while (kinds_[(i + chain.edges) % n] != Kind::kOut) {
          const std::size_t e = (i + chain.edges) % n;
          // A vertex inside the run on a side, with edges into the box on
          // both sides of it: the boundary touches the side there, and the
          // walk along the side would pass through it.
          if (chain.edges > 0 && on_side(ring[e]) && kinds_[e] == Kind::kIn &&
              kinds_[(e + n - 1) % n] == Kind::kIn)
            return false;
          ++chain.edges;
        }
        chain.types.assign(chain.edges, EdgeType::kBorder);
        const auto& types = polygon.edge_types[r];
        for (std::size_t k = 0; k < chain.edges; ++k)
          if (kinds_[(i + k) % n] == Kind::kIn) chain.types[k] = types[(i + k) % n];
        chain.start = position(ring[i]);
        chain.end = position(ring[(i + chain.edges) % n]);
        chains_.push_back(std::move(chain));
      }
    }
    // Two vertices at one point of a side: split_at_grid puts crossings
    // within 1e-9 m of a line on it, which can make a polygon touch itself
    // there (two crossings put on one corner). Inside or outside is then not
    // the walk's to say.
    std::sort(on_sides_.begin(), on_sides_.end(), [](const Point& a, const Point& b) {
      return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
    });
    if (std::adjacent_find(on_sides_.begin(), on_sides_.end(), [](const Point& a, const Point& b) {
          return a.x() == b.x() && a.y() == b.y();
        }) != on_sides_.end())
      return false;
    TypedMultiPolygon pieces;
    if (outer_whole) {
      // The whole polygon, holes and all (inside its outer ring, so in the box).
      if (!chains_.empty()) return false;  // a hole beyond its outer ring: not a valid polygon
      TypedPolygon whole = polygon;
      for (std::size_t r = 0; r < rings; ++r) retype_sides(ring_of(r), whole.edge_types[r]);
      out.push_back(std::move(whole));
      return true;
    }
    if (chains_.empty()) {
      // No edge reaches into the box but the whole holes' (checked alone
      // below): the box is inside the polygon or outside it, as its centre is.
      const Point centre((x0_ + x1_) / 2, (y0_ + y1_) / 2);
      bool inside = false;
      for (const std::size_t r : open_rings_) {
        const Ring& ring = ring_of(r);
        for (std::size_t i = 0; i + 1 < ring.size(); ++i) inside ^= ray_crosses(centre, ring[i], ring[i + 1]);
      }
      if (!inside) {
        if (!whole_holes_.empty()) return false;  // a hole in the box, the box outside: not valid
        return true;
      }
      TypedPolygon box;
      box.geometry.outer().assign(corners_.begin(), corners_.end());
      box.geometry.outer().push_back(corners_[0]);
      box.edge_types.assign(1, std::vector<EdgeType>(4, EdgeType::kBorder));
      pieces.push_back(std::move(box));
    } else if (!stitch(ring_of, pieces)) {
      return false;
    }
    if (!whole_holes_.empty()) {
      // Holes inside the box are inside one of the pieces: without a test
      // which, only where there is one.
      if (pieces.size() != 1) return false;
      for (const std::size_t r : whole_holes_) {
        pieces[0].geometry.inners().push_back(ring_of(r));
        pieces[0].edge_types.push_back(polygon.edge_types[r]);
        retype_sides(ring_of(r), pieces[0].edge_types.back());
      }
    }
    // A hole may touch its outer ring or another hole at a point (valid),
    // and a piece's ring may then pass that point twice or through a vertex
    // of a hole: the overlay cuts such rings apart, the walk leaves them to
    // it. Only polygons with holes can (a scan has none, a band rarely).
    if (!polygon.geometry.inners().empty() && !is_clearly_valid(pieces)) return false;
    for (auto& piece : pieces) out.push_back(std::move(piece));
    return true;
  }

 private:
  enum class Kind : std::uint8_t { kIn, kOnSide, kOut };
  struct Chain {
    std::size_t ring, first, edges;
    std::vector<EdgeType> types;
    SidePosition start, end;
  };

  bool outside(const Point& p) const { return p.x() < x0_ || p.x() > x1_ || p.y() < y0_ || p.y() > y1_; }
  // A vertex within kNearSideM of the box's sides but not on them, or on a
  // side within kNearSideM of a corner but not at it. Features that small
  // near the sides are below the overlay's grid, which snaps them away: a
  // piece would keep them as slivers or spikes, and split_at_grid may have
  // moved a vertex there by up to 1e-9 m (onto a line), which can fold such
  // a feature over.
  static constexpr double kNearSideM = kOverlayMovesM;
  bool near_sides(const Point& p) const {
    const double dx = std::max({x0_ - p.x(), 0.0, p.x() - x1_}), dy = std::max({y0_ - p.y(), 0.0, p.y() - y1_});
    if (dx > 0.0 || dy > 0.0) return dx * dx + dy * dy < kNearSideM * kNearSideM;  // outside
    const double gap = std::min(std::min(p.x() - x0_, x1_ - p.x()), std::min(p.y() - y0_, y1_ - p.y()));
    if (gap > 0.0) return gap < kNearSideM;  // inside
    for (const Point& corner : corners_) {  // on a side
      const double d2 = bg::comparable_distance(p, corner);
      if (d2 > 0.0 && d2 < kNearSideM * kNearSideM) return true;
    }
    return false;
  }
  bool on_side(const Point& p) const {
    return !outside(p) && (p.x() == x0_ || p.x() == x1_ || p.y() == y0_ || p.y() == y1_);
  }
  // The side line both points lie on, counter-clockwise along it or not;
  // nullopt if they share none.
  std::optional<bool> along_side(const Point& p, const Point& q) const {
    if (p.y() == y0_ && q.y() == y0_) return q.x() > p.x();
    if (p.x() == x1_ && q.x() == x1_) return q.y() > p.y();
    if (p.y() == y1_ && q.y() == y1_) return q.x() < p.x();
    if (p.x() == x0_ && q.x() == x0_) return q.y() < p.y();
    return std::nullopt;
  }
  // What edge p-q is to the box; nullopt where the walk cannot tell (see
  // tile_grid.hpp).
  std::optional<Kind> classify(const Point& p, const Point& q) const {
    const bool p_out = outside(p), q_out = outside(q);
    if (!p_out && !q_out) {
      // Along a side clockwise: the polygon's inside is beyond the side. Left
      // to the overlay: another edge of the polygon may run along the same
      // stretch the other way (a spike a hair wide, valid to Boost), which
      // the overlay's grid closes and the walk would take for a side.
      if (const auto ccw = along_side(p, q)) return *ccw ? std::optional(Kind::kOnSide) : std::nullopt;
      return Kind::kIn;  // two points of a convex box not on one side: its interior between them
    }
    if (p_out && q_out) {
      // Both beyond the box: the edge must not pass through it.
      const bool meets = std::max(p.x(), q.x()) > x0_ && std::min(p.x(), q.x()) < x1_ &&
                         std::max(p.y(), q.y()) > y0_ && std::min(p.y(), q.y()) < y1_;
      return meets ? std::nullopt : std::optional(Kind::kOut);
    }
    // From a side straight out: the inner point on a side, the outer one on
    // the far side of that side's line (not on it: an edge along the line).
    const Point& in = p_out ? q : p;
    const Point& out = p_out ? p : q;
    if ((in.x() == x0_ && out.x() < x0_) || (in.x() == x1_ && out.x() > x1_) || (in.y() == y0_ && out.y() < y0_) ||
        (in.y() == y1_ && out.y() > y1_))
      return Kind::kOut;
    return std::nullopt;
  }
  SidePosition position(const Point& p) const {
    if (p.y() == y0_ && p.x() < x1_) return {0, p.x()};
    if (p.x() == x1_ && p.y() < y1_) return {1, p.y()};
    if (p.y() == y1_ && p.x() > x0_) return {2, -p.x()};
    return {3, -p.y()};
  }
  void retype_sides(const Ring& ring, std::vector<EdgeType>& types) const {
    for (std::size_t i = 0; i + 1 < ring.size(); ++i)
      if (along_side(ring[i], ring[i + 1])) types[i] = EdgeType::kBorder;
  }

  // Joins the runs into rings: from each run's end counter-clockwise along
  // the sides (through the corners passed) to the next run's start.
  template <class RingOf>
  bool stitch(RingOf&& ring_of, TypedMultiPolygon& pieces) {
    const std::size_t m = chains_.size();
    // Two runs meeting at one point of a side (or nearer than the overlay's
    // grid): which joins which is not the walk's to say.
    ends_.clear();
    for (const Chain& c : chains_) ends_.push_back(c.start), ends_.push_back(c.end);
    std::sort(ends_.begin(), ends_.end());
    if (std::adjacent_find(ends_.begin(), ends_.end(), [](const SidePosition& a, const SidePosition& b) {
          return a.side == b.side && b.along - a.along < kNearSideM;
        }) != ends_.end())
      return false;
    order_.resize(m);
    for (std::size_t k = 0; k < m; ++k) order_[k] = k;
    std::sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) { return chains_[a].start < chains_[b].start; });
    auto next_of = [&](std::size_t c) {
      const auto it = std::upper_bound(order_.begin(), order_.end(), chains_[c].end,
                                       [&](const SidePosition& e, std::size_t k) { return e < chains_[k].start; });
      return it == order_.end() ? order_.front() : *it;
    };
    used_.assign(m, 0);
    for (std::size_t first = 0; first < m; ++first) {
      if (used_[first]) continue;
      TypedPolygon piece;
      Ring& ring = piece.geometry.outer();
      piece.edge_types.resize(1);
      std::vector<EdgeType>& types = piece.edge_types[0];
      std::size_t c = first;
      do {
        if (used_[c]) return false;  // a run reached twice: the sides' order does not close
        used_[c] = 1;
        const Chain& chain = chains_[c];
        const Ring& source = ring_of(chain.ring);
        const std::size_t n = source.size() - 1;
        for (std::size_t k = 0; k < chain.edges; ++k) {
          ring.push_back(source[(chain.first + k) % n]);
          types.push_back(chain.types[k]);
        }
        const std::size_t next = next_of(c);
        const SidePosition& e = chain.end;
        const SidePosition& s = chains_[next].start;
        const std::size_t stretch_first = ring.size();
        ring.push_back(source[(chain.first + chain.edges) % n]);
        types.push_back(EdgeType::kBorder);
        if (!(s.side == e.side && s.along > e.along)) {
          int k = e.side;
          do {
            k = (k + 1) % 4;
            if (position(corners_[static_cast<std::size_t>(k)]) != s) {
              ring.push_back(corners_[static_cast<std::size_t>(k)]);
              types.push_back(EdgeType::kBorder);
            }
          } while (k != s.side);
        }
        // The stretch along the sides from the run's end to the next run's
        // start: a piece shorter than the overlay's grid would be a sliver.
        const Point& stretch_end = ring_of(chains_[next].ring)[chains_[next].first];
        for (std::size_t v = stretch_first; v < ring.size(); ++v)
          if (bg::comparable_distance(ring[v], v + 1 < ring.size() ? ring[v + 1] : stretch_end) <
              kNearSideM * kNearSideM)
            return false;
        c = next;
      } while (c != first);
      ring.push_back(ring.front());
      // Counter-clockwise, as the walk makes every piece of a valid polygon.
      if (!(bg::area(ring) > 0.0)) return false;
      pieces.push_back(std::move(piece));
    }
    return true;
  }

  double x0_ = 0.0, y0_ = 0.0, x1_ = 0.0, y1_ = 0.0;
  std::array<Point, 4> corners_;
  std::vector<Kind> kinds_;
  std::vector<Chain> chains_;
  std::vector<std::size_t> whole_holes_, order_;
  std::vector<std::size_t> open_rings_;  // rings with no kept edge: for the box's own test
  std::vector<SidePosition> ends_;
  std::vector<char> used_;
  std::vector<Point> on_sides_;  // the vertices on a side
};

}  // namespace

std::int32_t TileGrid::index(double v) const {
  // The k with line(k) <= v < line(k + 1): the plain quotient, put right
  // where line()'s rounding onto the overlay's grid moved the line across v.
  auto k = static_cast<std::int64_t>(std::floor((v - origin_m) / size_m));
  if (line(k) > v) --k;
  else if (line(k + 1) <= v) ++k;
  return static_cast<std::int32_t>(k);
}

Box TileGrid::box(const TileKey& key) const {
  return Box(Point(line(key.first), line(key.second)), Point(line(key.first + 1), line(key.second + 1)));
}

std::pair<TileKey, TileKey> TileGrid::range(const Box& envelope) const {
  return {{index(envelope.min_corner().x()), index(envelope.min_corner().y())},
          {index(envelope.max_corner().x()), index(envelope.max_corner().y())}};
}

void split_at_grid(MultiPolygon& geometry, double cell_m, double origin_m) {
  const TileGrid grid{cell_m, origin_m};
  for (auto& polygon : geometry) {
    split_ring(polygon.outer(), nullptr, grid);
    for (auto& inner : polygon.inners()) split_ring(inner, nullptr, grid);
  }
}

void split_at_grid(TypedPolygon& polygon, double cell_m, double origin_m) {
  const TileGrid grid{cell_m, origin_m};
  split_ring(polygon.geometry.outer(), &polygon.edge_types[0], grid);
  for (std::size_t k = 0; k < polygon.geometry.inners().size(); ++k)
    split_ring(polygon.geometry.inners()[k], &polygon.edge_types[1 + k], grid);
}

bool clip_split_to_tile(const TypedPolygon& polygon, const Box& tile, TypedMultiPolygon& out) {
  thread_local TileClipper clipper;  // its scratch keeps its capacity: this runs per tile of every insert
  clipper.set_box(tile);
  return clipper.clip(polygon, out);
}

}  // namespace pex::mapping
