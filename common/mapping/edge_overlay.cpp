#include "mapping/edge_overlay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <boost/multiprecision/cpp_int.hpp>

#include "mapping/typed_ops.hpp"

namespace pex::mapping {

namespace {

using I64 = std::int64_t;
__extension__ typedef __int128 I128;  // GCC and Clang; -Wpedantic knows no 128-bit type

constexpr std::uint32_t kNone = 0xffffffffu;
constexpr double kGridScale = 1 << kOverlayGridBits;
// The operands are read on a much finer grid (2^-40 m: a double's own
// resolution at the largest coordinate taken, so only fractions of a
// picometre are rounded), and snap rounding takes them from there to the
// overlay's grid: rounding each vertex straight to a cell could move a
// vertex that touches another edge of its own operand across that edge.
constexpr int kFineBits = 40;
constexpr int kFinePerCellBits = kFineBits - kOverlayGridBits;
constexpr std::int64_t kFinePerCell = std::int64_t{1} << kFinePerCellBits;
constexpr double kFineScale = static_cast<double>(std::int64_t{1} << kFineBits);
constexpr double kMaxFine = kOverlayMaxCoordinateM * kFineScale;  // 2^53

// A point in fine units (operands' vertices) or in cells (the output).
struct IPoint {
  I64 x = 0, y = 0;
  bool operator==(const IPoint&) const = default;
};

IPoint operator-(const IPoint& a, const IPoint& b) { return {a.x - b.x, a.y - b.y}; }

// Exact for both: fine coordinates are below 2^53, differences below 2^54.
I128 cross(const IPoint& a, const IPoint& b) { return I128(a.x) * b.y - I128(a.y) * b.x; }
I128 dot(const IPoint& a, const IPoint& b) { return I128(a.x) * b.x + I128(a.y) * b.y; }

int sign(I128 v) { return (v > 0) - (v < 0); }

Point to_point(const IPoint& p) { return Point(p.x / kGridScale, p.y / kGridScale); }

// The cell holding a fine point: cells are half-open, [c - 1/2, c + 1/2).
IPoint cell_of(const IPoint& fine) {
  constexpr I64 half = kFinePerCell / 2;
  return {(fine.x + half) >> kFinePerCellBits, (fine.y + half) >> kFinePerCellBits};
}
IPoint fine_of(const IPoint& cell) { return {cell.x * kFinePerCell, cell.y * kFinePerCell}; }

bool to_fine(const Point& p, IPoint& out) {
  const double x = std::round(p.x() * kFineScale), y = std::round(p.y() * kFineScale);
  if (!(std::abs(x) <= kMaxFine && std::abs(y) <= kMaxFine)) return false;  // also NaN
  out = {static_cast<I64>(x), static_cast<I64>(y)};
  return true;
}

struct InputEdge {
  IPoint p, q;    // fine
  IPoint cp, cq;  // their cells
  EdgeType type;
  std::uint8_t side;
  I64 min_x, max_x, min_y, max_y;  // box of cp, cq
};

struct InputRing {
  std::uint8_t side;
  std::uint32_t first_edge, last_edge;  // [first, last) in edges
  std::uint32_t first_piece = 0, last_piece = 0;
  I64 min_x, max_x, min_y, max_y;
};

struct FineBox {
  I64 min_x, max_x, min_y, max_y;
};

// A run of vertices farther than this beyond the other side's box is
// collapsed where the operation drops it (Overlay::add_side): beyond the
// cells whose edges far_and_dropped leaves unbent, so the edge made of it
// is not bent either.
constexpr I64 kCollapseCells = 32;

// A hot pixel an edge is bent through.
struct Bend {
  std::uint32_t edge;
  IPoint at;
};

// A piece of an input edge between consecutive hot pixels.
struct Piece {
  std::uint32_t from, to;  // vertex ids
  EdgeType type;
  std::uint8_t side;
  // +1: the other side has it in the same direction, -1: opposite;
  // 2: its own side has it the other way round (a sliver collapsed by
  // rounding: both copies bound nothing and are dropped).
  std::int8_t coincident = 0;
  bool keep = false;
};

// Whether segment p-q (fine) meets the cell c: the half-open square
// [c - 1/2, c + 1/2)^2, so that each point of the plane is in one cell.
// Exact: the segment meets the cell shrunk by an infinitesimal d on its
// open sides unless its box misses it or its line has all four corners
// strictly on one side; a corner on the line takes the sign its
// infinitesimal move gives it.
bool passes_through(const IPoint& p, const IPoint& q, const IPoint& c) {
  constexpr I64 half = kFinePerCell / 2;
  const IPoint centre = fine_of(c);
  const I64 x0 = centre.x - half, x1 = centre.x + half, y0 = centre.y - half, y1 = centre.y + half;
  if (std::max(p.x, q.x) < x0 || std::min(p.x, q.x) >= x1 || std::max(p.y, q.y) < y0 || std::min(p.y, q.y) >= y1)
    return false;
  const I64 dx = q.x - p.x, dy = q.y - p.y;
  // cross(d, corner - p) at (x0, y0); moving the corner by (+s, 0) adds
  // -dy*s, by (0, +s) adds dx*s. The open sides' corners are x1 - d, y1 - d.
  const I128 v00 = I128(dx) * (y0 - p.y) - I128(dy) * (x0 - p.x);
  constexpr I64 w = kFinePerCell;
  auto side = [](I128 v, I64 nudge) { return v != 0 ? sign(v) : (nudge > 0) - (nudge < 0); };
  const int s00 = side(v00, 0);
  const int s10 = side(v00 - I128(dy) * w, dy);
  const int s01 = side(v00 + I128(dx) * w, -dx);
  const int s11 = side(v00 + I128(dx) * w - I128(dy) * w, dy - dx);
  return !((s00 > 0 && s10 > 0 && s01 > 0 && s11 > 0) || (s00 < 0 && s10 < 0 && s01 < 0 && s11 < 0));
}

// The cell holding the crossing of p-q and r-s (fine), which cross
// properly. The crossing is p + e n / m; its coordinates' numerators need
// more than 128 bits (a crossing is rare enough for 256).
IPoint crossing_cell(const IPoint& p, const IPoint& q, const IPoint& r, const IPoint& s) {
  using boost::multiprecision::int256_t;
  const IPoint e = q - p, f = s - r;
  I128 n = cross(r - p, f), m = cross(e, f);
  if (m < 0) n = -n, m = -m;
  // First in long double (at least 64 bits of mantissa): n / m is good to
  // about 2^-62, times an edge under 2^54 fine units that is under a fine
  // unit, so it decides the cell unless the crossing is within 2^10 fine
  // units of a cell's side; then exactly.
  {
    const long double t = static_cast<long double>(n) / static_cast<long double>(m);
    auto cell = [&](I64 from, I64 along, I64& out) {
      const long double x = static_cast<long double>(from) + static_cast<long double>(along) * t;
      const long double u = x / kFinePerCell + 0.5L;
      const long double f = std::floor(u);
      if (u - f < 0x1p-10L || f + 1 - u < 0x1p-10L) return false;
      out = static_cast<I64>(f);
      return true;
    };
    IPoint c;
    if (cell(p.x, e.x, c.x) && cell(p.y, e.y, c.y)) return c;
  }
  // floor((x + half) / kFinePerCell) = floor((p m + e n + half m) / (kFinePerCell m)).
  const int256_t n256(n), m256(m), den = m256 * kFinePerCell;
  auto cell = [&](I64 from, I64 along) {
    const int256_t num = int256_t(from) * m256 + int256_t(along) * n256 + m256 * (kFinePerCell / 2);
    int256_t q256 = num / den;
    if (num % den != 0 && num < 0) --q256;
    return static_cast<I64>(q256);
  };
  return {cell(p.x, e.x), cell(p.y, e.y)};
}

// The counter-clockwise angle from direction r to direction d as an ordered
// class and a comparison within it, without rounding: class 0 the same
// direction, 1 strictly left (0, pi), 2 opposite, 3 strictly right (pi, 2 pi).
int angle_class(const IPoint& r, const IPoint& d) {
  const int c = sign(cross(r, d));
  if (c > 0) return 1;
  if (c < 0) return 3;
  return dot(r, d) > 0 ? 0 : 2;
}
// True if turning counter-clockwise from r one meets d1 before d2.
bool turns_before(const IPoint& r, const IPoint& d1, const IPoint& d2) {
  const int c1 = angle_class(r, d1), c2 = angle_class(r, d2);
  if (c1 != c2) return c1 < c2;
  return (c1 == 1 || c1 == 3) && cross(d1, d2) > 0;
}

// Whether the ray from (x2 / 2, y2 / 2) (doubled units) to +x crosses
// segment p-q, half-open in y so that a ray through a vertex counts it once:
// the point is left of an upward segment or right of a downward one.
bool crosses_ray(const IPoint& p, const IPoint& q, I64 x2, I64 y2) {
  if ((2 * p.y > y2) == (2 * q.y > y2)) return false;
  const I128 c = I128(q.x - p.x) * (y2 - 2 * p.y) - I128(x2 - 2 * p.x) * (q.y - p.y);
  return q.y > p.y ? c > 0 : c < 0;
}

std::uint64_t hash_of(const IPoint& p) {
  const auto bx = static_cast<std::uint64_t>(p.x), by = static_cast<std::uint64_t>(p.y);
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

// A uniform grid of n by n buckets over a box (in cells), each a power of
// two of cells wide and high (a shift finds one: a division per look-up was
// a tenth of an insert).
struct Buckets {
  int n = 1;
  I64 min_x = 0, min_y = 0;
  int shift_x = 0, shift_y = 0;

  void set(I64 box_min_x, I64 box_max_x, I64 box_min_y, I64 box_max_y, int count) {
    n = count;
    min_x = box_min_x;
    min_y = box_min_y;
    auto shift_for = [&](I64 extent) {
      int shift = 0;
      while ((extent >> shift) >= n) ++shift;
      return shift;
    };
    shift_x = shift_for(box_max_x - box_min_x);
    shift_y = shift_for(box_max_y - box_min_y);
  }
  std::size_t size() const { return static_cast<std::size_t>(n) * static_cast<std::size_t>(n); }
  int col(I64 x) const { return static_cast<int>(std::clamp<I64>((x - min_x) >> shift_x, 0, n - 1)); }
  int row(I64 y) const { return static_cast<int>(std::clamp<I64>((y - min_y) >> shift_y, 0, n - 1)); }
  std::size_t of(const IPoint& c) const { return static_cast<std::size_t>(row(c.y) * n + col(c.x)); }

  // fn(bucket) for every bucket the band of segment p-q (in cells; the
  // points within `margin` cells of it, margin at least 2) can reach: row by
  // row, the columns of the part of the segment inside the row's slab,
  // widened. The outer rows and columns reach to infinity. The slab's
  // columns are found in double, which errs far less than a cell.
  template <class Fn>
  void for_each(const IPoint& p, const IPoint& q, I64 margin, Fn&& fn) const {
    const I64 lo_x = std::min(p.x, q.x), hi_x = std::max(p.x, q.x);
    const I64 lo_y = std::min(p.y, q.y), hi_y = std::max(p.y, q.y);
    const int first_row = row(lo_y - margin), last_row = row(hi_y + margin);
    const int first_col = col(lo_x - margin), last_col = col(hi_x + margin);
    if (first_row == last_row || first_col == last_col || p.y == q.y) {
      for (int r = first_row; r <= last_row; ++r)
        for (int c = first_col; c <= last_col; ++c) fn(static_cast<std::size_t>(r * n + c));
      return;
    }
    const double dx = static_cast<double>(q.x - p.x), dy = static_cast<double>(q.y - p.y);
    const I64 height = I64{1} << shift_y;
    for (int r = first_row; r <= last_row; ++r) {
      const double slab_lo = static_cast<double>(r == 0 ? lo_y : std::max(lo_y, min_y + r * height - margin));
      const double slab_hi =
          static_cast<double>(r == n - 1 ? hi_y : std::min(hi_y, min_y + (r + 1) * height + margin));
      const double ta = std::clamp((slab_lo - static_cast<double>(p.y)) / dy, 0.0, 1.0);
      const double tb = std::clamp((slab_hi - static_cast<double>(p.y)) / dy, 0.0, 1.0);
      const double xa = static_cast<double>(p.x) + ta * dx, xb = static_cast<double>(p.x) + tb * dx;
      const int c0 = std::max(first_col, col(static_cast<I64>(std::floor(std::min(xa, xb))) - margin));
      const int c1 = std::min(last_col, col(static_cast<I64>(std::ceil(std::max(xa, xb))) + margin));
      for (int c = c0; c <= c1; ++c) fn(static_cast<std::size_t>(r * n + c));
    }
  }
};

// The working state of one overlay. Its buffers keep their capacity from
// call to call (one per thread, see overlay()): allocation was a fifth of the
// cost of small overlays.
class Overlay {
 public:
  OverlayResult run(std::span<const RingRef> a, std::span<const RingRef> b, OverlayOp op,
                    const std::optional<Box>& border_box, const std::optional<EdgeType> (&side_types)[2]) {
    clear();
    // What `op` drops of each side far outside the other (see add_side).
    std::optional<FineBox> around[2];
    if (op != OverlayOp::kUnion) around[1] = far_box_of(a);
    if (op == OverlayOp::kIntersection) around[0] = far_box_of(b);
    if (!add_side(a, 0, side_types[0], around[0]) || !add_side(b, 1, side_types[1], around[1])) {
      OverlayResult result;
      result.error = "overlay: a coordinate is not finite or beyond " +
                     std::to_string(static_cast<int>(kOverlayMaxCoordinateM)) + " m";
      return result;
    }
    set_boxes();
    find_hot_pixels();
    bend_edges(op);
    make_pieces();
    index_incidence();
    mark_coincident();
    classify(op);
    return link(border_box);
  }

 private:
  std::vector<InputEdge> edges_;
  std::vector<InputRing> rings_;
  std::vector<IPoint> hot_;  // hot cells: of every vertex, of every crossing of a with b
  std::vector<std::uint32_t> bucket_start_, bucket_edges_;  // b's edges near the meet box by bucket
  std::vector<std::uint32_t> hot_start_, hot_cells_;        // hot cells by bucket
  std::vector<IPoint> hot_by_bucket_;                       // hot_[hot_cells_[m]]: read without the hop
  std::vector<std::uint32_t> tested_by_;  // by edge of b: the edge of a that last met it
  std::vector<std::uint32_t> candidates_;  // scratch of find_hot_pixels
  std::vector<Bend> bends_;               // by edge, then along it
  std::vector<IPoint> path_, found_, edge_near_, piece_near_;  // scratch of bend_edges
  std::vector<IPoint> vertices_;
  std::vector<std::uint8_t> vertex_sides_;  // bit s: a piece of side s starts or ends here
  // Open-addressing table of vertex ids by coordinates (a hash map with a
  // node per vertex cost more than the rest of the overlay).
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
  // The emitted rings' pieces, in loop_pieces_ from `first` on.
  struct Loop {
    std::uint32_t first, size;
    I128 twice_area;
  };
  std::vector<Loop> outer_loops_, hole_loops_;  // in the order of result.polygons, of the holes
  std::vector<std::uint32_t> loop_pieces_;
  struct Slabs {
    bool built = false;
    I64 min_y = 0, max_y = 0, height = 1;
    std::vector<std::uint32_t> start, pieces;  // pieces by row
  };
  Slabs slabs_[2];
  // Where the sides can cross: the overlap of their boxes (in cells),
  // widened by a cell.
  I64 meet_min_x_ = 0, meet_max_x_ = -1, meet_min_y_ = 0, meet_max_y_ = -1;
  I64 side_box_[2][4] = {};  // each side's box in cells: min x, max x, min y, max y
  // Buckets over both sides: of b's edges near the meet box (to find
  // crossings) and, finer, of the hot pixels.
  Buckets edge_buckets_, hot_buckets_;

  void clear() {
    slabs_[0].built = slabs_[1].built = false;
    edges_.clear();
    rings_.clear();
    hot_.clear();
    bends_.clear();
    vertices_.clear();
    vertex_sides_.clear();
    pieces_.clear();
  }

  // The box of `rings` in fine units, widened by kCollapseCells: a side's
  // runs of vertices beyond it are collapsed (add_side). nullopt if a
  // coordinate is out of range (add_side refuses it).
  static std::optional<FineBox> far_box_of(std::span<const RingRef> rings) {
    double lo_x = std::numeric_limits<double>::infinity(), hi_x = -lo_x, lo_y = lo_x, hi_y = -lo_x;
    for (const RingRef& ref : rings)
      for (const Point& p : *ref.ring) {
        lo_x = std::min(lo_x, p.x()), hi_x = std::max(hi_x, p.x());
        lo_y = std::min(lo_y, p.y()), hi_y = std::max(hi_y, p.y());
      }
    IPoint lo, hi;
    if (!to_fine(Point(lo_x, lo_y), lo) || !to_fine(Point(hi_x, hi_y), hi)) return std::nullopt;
    constexpr I64 widen = kCollapseCells * kFinePerCell;
    return FineBox{lo.x - widen, hi.x + widen, lo.y - widen, hi.y + widen};
  }

  // Adds the rings' edges. With `collapse` (the other side's box, widened,
  // where `op` drops this side's pieces outside the other side), a run of
  // consecutive vertices that all lie beyond one of its sides becomes one
  // edge from its first vertex to its last. The run and that edge lie in
  // one half-plane the other side does not reach, so they are dropped
  // alike, and together they close a loop there, which a ray from any point
  // tested (near the other side) crosses an even number of times. The edge
  // can cross others of its side there (a precondition the overlay needs
  // only where pieces are kept). Most of a scan's vertices lie outside the
  // tile it is clipped to.
  bool add_side(std::span<const RingRef> rings, std::uint8_t side, std::optional<EdgeType> type,
                const std::optional<FineBox>& collapse) {
    // Bit per side of the box a point lies strictly beyond.
    auto beyond = [&](const IPoint& p) -> unsigned {
      if (!collapse) return 0;
      return unsigned(p.x < collapse->min_x) | unsigned(p.x > collapse->max_x) << 1 |
             unsigned(p.y < collapse->min_y) << 2 | unsigned(p.y > collapse->max_y) << 3;
    };
    for (const RingRef& ref : rings) {
      const Ring& ring = *ref.ring;
      const std::vector<EdgeType>& types = *ref.types;
      if (ring.size() < 2) continue;
      InputRing r{side, static_cast<std::uint32_t>(edges_.size()), 0, 0, 0, 0, 0, 0, 0};
      r.min_x = r.min_y = std::numeric_limits<I64>::max();
      r.max_x = r.max_y = std::numeric_limits<I64>::min();
      auto add_edge = [&](const IPoint& p, const IPoint& q, EdgeType edge_type) {
        if (p == q) return;  // repeated
        const IPoint cp = cell_of(p), cq = cell_of(q);
        InputEdge e{p, q, cp, cq, type.value_or(edge_type), side, std::min(cp.x, cq.x), std::max(cp.x, cq.x),
                    std::min(cp.y, cq.y), std::max(cp.y, cq.y)};
        r.min_x = std::min(r.min_x, e.min_x);
        r.max_x = std::max(r.max_x, e.max_x);
        r.min_y = std::min(r.min_y, e.min_y);
        r.max_y = std::max(r.max_y, e.max_y);
        edges_.push_back(e);
      };
      IPoint start;  // where the next edge starts
      if (!to_fine(ring.front(), start)) return false;
      // The run from `start` to `last` (the vertex before ring[i]), all
      // beyond the sides in `run`; last == start when it is one vertex.
      unsigned run = beyond(start);
      IPoint last = start;
      for (std::size_t i = 1; i < ring.size(); ++i) {
        IPoint q;
        if (!to_fine(ring[i], q)) return false;
        const bool closing = i + 1 == ring.size();  // the ring's first vertex again: kept
        const unsigned where = beyond(q);
        if (!closing && (run & where) != 0) {
          last = q;
          run &= where;
          continue;
        }
        if (last != start) {  // the run ends at `last`: one edge to it, and its last edge from it
          add_edge(start, last, type ? *type : types[i - 2]);
          start = last;
        }
        add_edge(start, q, type ? *type : types[i - 1]);
        start = last = q;
        run = where;
      }
      r.last_edge = static_cast<std::uint32_t>(edges_.size());
      if (r.last_edge > r.first_edge) rings_.push_back(r);
    }
    return true;
  }

  // The meet box (where the sides can cross) and the cell grid over
  // everything (where edges are bent through hot pixels).
  void set_boxes() {
    I64 box[3][4];
    for (auto& b : box) {
      b[0] = b[2] = std::numeric_limits<I64>::max();
      b[1] = b[3] = std::numeric_limits<I64>::min();
    }
    for (const auto& r : rings_) {
      for (I64* b : {box[r.side], box[2]}) {
        b[0] = std::min(b[0], r.min_x);
        b[1] = std::max(b[1], r.max_x);
        b[2] = std::min(b[2], r.min_y);
        b[3] = std::max(b[3], r.max_y);
      }
    }
    for (int side = 0; side < 2; ++side) std::copy(box[side], box[side] + 4, side_box_[side]);
    meet_min_x_ = std::max(box[0][0], box[1][0]) - 1;
    meet_max_x_ = std::min(box[0][1], box[1][1]) + 1;
    meet_min_y_ = std::max(box[0][2], box[1][2]) - 1;
    meet_max_y_ = std::min(box[0][3], box[1][3]) + 1;
    if (rings_.empty()) return;
    const int edge_count = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(edges_.size()) / 4.0)), 1, 64);
    edge_buckets_.set(box[2][0], box[2][1], box[2][2], box[2][3], edge_count);
    // Hot pixels lie along the rings, a curve: a bucket the curve passes
    // holds about its length over the buckets' side, so these are finer.
    const int hot_count = std::clamp(static_cast<int>(2.0 * std::sqrt(static_cast<double>(edges_.size()))), 1, 256);
    hot_buckets_.set(box[2][0], box[2][1], box[2][2], box[2][3], hot_count);
  }
  // Whether edge e is dropped by `op` however it is bent: an intersection
  // keeps no piece outside the other side, a difference no piece of b
  // outside a, and e lies farther outside the other side's box than bending
  // moves a piece (kFarCells, many times the drift the area checks allow).
  // Such an edge is not bent. The hot pixels of its ends stay and bend the
  // edges near them; its pieces stay in the point-in-polygon tests, where
  // bent or not it closes a thin loop far from every point tested, which a
  // ray crosses an even number of times. In a clip of a scan to one of the
  // tiles it spans, most of the scan's edges are such.
  bool far_and_dropped(const InputEdge& e, OverlayOp op) const {
    constexpr I64 kFarCells = 16;
    if (op != OverlayOp::kIntersection && !(op == OverlayOp::kDifference && e.side == 1)) return false;
    const I64* other = side_box_[1 - e.side];
    return e.max_x < other[0] - kFarCells || e.min_x > other[1] + kFarCells || e.max_y < other[2] - kFarCells ||
           e.min_y > other[3] + kFarCells;
  }
  bool meets_nothing() const { return meet_max_x_ < meet_min_x_ || meet_max_y_ < meet_min_y_; }
  bool near_meet_box(const InputEdge& e) const {
    return e.max_x >= meet_min_x_ && e.min_x <= meet_max_x_ && e.max_y >= meet_min_y_ && e.min_y <= meet_max_y_;
  }
  // The hot pixels: the cell of every vertex and of every proper crossing
  // of an edge of a with one of b (the operands' own edges do not cross).
  // Crossings are found through the bucket grid: b's edges near the meet
  // box are listed in the buckets their band reaches, each edge of a near
  // it visits its own, and a pair met in several buckets is tested once
  // (tested_by_).
  void find_hot_pixels() {
    if (rings_.empty()) return;
    for (const auto& e : edges_) hot_.push_back(e.cp);  // each edge's end starts the next
    if (!meets_nothing()) {
      build_lists(edge_buckets_.size(), bucket_start_, bucket_edges_, fill_, [&](auto&& emit) {
        for (std::uint32_t k = 0; k < edges_.size(); ++k) {
          const InputEdge& e = edges_[k];
          if (e.side == 1 && near_meet_box(e))
            edge_buckets_.for_each(e.cp, e.cq, 2, [&](std::size_t b) { emit(b, k); });
        }
      });
      tested_by_.assign(edges_.size(), kNone);
      candidates_.resize(edges_.size());  // a bucket lists an edge once at most
      // Plain pointers and a copy of the buckets: through the members (of a
      // thread_local), the stores to tested_by_ made every read reload them.
      const InputEdge* const edges = edges_.data();
      const std::uint32_t* const bucket_start = bucket_start_.data();
      const std::uint32_t* const bucket_edges = bucket_edges_.data();
      std::uint32_t* const tested_by = tested_by_.data();
      std::uint32_t* const candidates = candidates_.data();
      const Buckets buckets = edge_buckets_;
      for (std::uint32_t k = 0; k < edges_.size(); ++k) {
        const InputEdge& e = edges[k];
        if (e.side != 0 || !near_meet_box(e)) continue;
        const IPoint ed = e.q - e.p;
        buckets.for_each(e.cp, e.cq, 2, [&](std::size_t b) {
          const std::uint32_t first = bucket_start[b], last = bucket_start[b + 1];
          // The edges whose boxes meet e's and that no earlier bucket
          // brought are listed first, without a branch per edge: which
          // ones do is a coin toss to the branch predictor.
          std::uint32_t* const listed = candidates;
          std::size_t count = 0;
          const I64 lo_x = e.min_x, hi_x = e.max_x, lo_y = e.min_y, hi_y = e.max_y;
          for (std::uint32_t m = first; m < last; ++m) {
            const std::uint32_t j = bucket_edges[m];
            const InputEdge& f = edges[j];
            listed[count] = j;
            count += static_cast<std::size_t>((tested_by[j] != k) & (f.max_x >= lo_x) & (f.min_x <= hi_x) &
                                              (f.max_y >= lo_y) & (f.min_y <= hi_y));
            tested_by[j] = k;
          }
          for (std::size_t c = 0; c < count; ++c) {
            const InputEdge& f = edges[listed[c]];
            const int d1 = sign(cross(ed, f.p - e.p)), d2 = sign(cross(ed, f.q - e.p));
            if (d1 * d2 >= 0) continue;
            const IPoint fd = f.q - f.p;
            const int d3 = sign(cross(fd, e.p - f.p)), d4 = sign(cross(fd, e.q - f.p));
            if (d3 * d4 >= 0) continue;
            hot_.push_back(crossing_cell(e.p, e.q, f.p, f.q));
          }
        });
      }
    }
    // Not made unique: a cell listed twice is found twice, and
    // hot_pixels_on drops the repeat.
    build_lists(hot_buckets_.size(), hot_start_, hot_cells_, fill_, [&](auto&& emit) {
      for (std::uint32_t k = 0; k < hot_.size(); ++k) emit(hot_buckets_.of(hot_[k]), k);
    });
    hot_by_bucket_.resize(hot_cells_.size());
    for (std::size_t m = 0; m < hot_cells_.size(); ++m) hot_by_bucket_[m] = hot_[hot_cells_[m]];
  }

  // The hot pixels within `margin` cells of the box of cells cp, cq but
  // those two, in `near`: every hot pixel a segment between those cells
  // passes but does not end in (margin 1), and those its bent pieces can
  // pass (below). Most edges have none.
  void gather_near(const IPoint& from, const IPoint& to, I64 margin, std::vector<IPoint>& near) {
    near.clear();
    // Copies in locals: `near` grows while the buckets are read, and the
    // compiler must assume that a store there changes what a reference or
    // a member (of a thread_local) holds.
    const IPoint cp = from, cq = to;
    const I64 min_x = std::min(cp.x, cq.x) - margin, max_x = std::max(cp.x, cq.x) + margin;
    const I64 min_y = std::min(cp.y, cq.y) - margin, max_y = std::max(cp.y, cq.y) + margin;
    const IPoint* const hot = hot_by_bucket_.data();
    const std::uint32_t* const hot_start = hot_start_.data();
    const Buckets buckets = hot_buckets_;
    buckets.for_each(cp, cq, margin + 1, [&](std::size_t b) {
      const IPoint* c = hot + hot_start[b];
      const IPoint* const last = hot + hot_start[b + 1];
      if (c == last) return;
      // Written without branches (each pixel stored, kept by moving the
      // end past it): whether a pixel is near is a coin toss to the branch
      // predictor, and its misses were most of the look-up.
      std::size_t kept = near.size();
      near.resize(kept + static_cast<std::size_t>(last - c));
      IPoint* const out = near.data();
      const I64 lo_x = min_x, hi_x = max_x, lo_y = min_y, hi_y = max_y;
      const IPoint end_a = cp, end_b = cq;
      for (; c != last; ++c) {
        const IPoint h = *c;
        out[kept] = h;
        kept += static_cast<std::size_t>((h.x >= lo_x) & (h.x <= hi_x) & (h.y >= lo_y) & (h.y <= hi_y) &
                                         ((h.x != end_a.x) | (h.y != end_a.y)) & ((h.x != end_b.x) | (h.y != end_b.y)));
      }
      near.resize(kept);
    });
  }

  // The hot pixels of `near` that segment p-q (fine; cp, cq their cells)
  // passes through but does not end in, in found_, ordered from p to q
  // (along a segment the cells it passes are met in the order of their
  // centres' projections; a cell listed twice is dropped).
  void hot_pixels_on(const IPoint& p, const IPoint& q, const IPoint& cp, const IPoint& cq,
                     const std::vector<IPoint>& near) {
    found_.clear();
    for (const IPoint& c : near)
      if (c != cp && c != cq && passes_through(p, q, c)) found_.push_back(c);
    if (found_.size() < 2) return;
    const IPoint d = q - p;
    std::sort(found_.begin(), found_.end(),
              [&](const IPoint& l, const IPoint& r) { return dot(fine_of(l) - p, d) < dot(fine_of(r) - p, d); });
    found_.erase(std::unique(found_.begin(), found_.end()), found_.end());
  }

  // Snap rounding: every edge is bent through the hot pixels it passes;
  // each bent piece is a new segment (between cell centres) that may pass
  // other hot pixels, so the pieces are bent again until none does
  // (iterated snap rounding). The bends are recorded by edge, in order.
  void bend_edges(OverlayOp op) {
    // A bent piece's ends are hot pixels the edge passes, within a cell of
    // its box; the pixels such a piece passes are within a cell of that:
    // gathering kNearMargin cells around the edge's box serves its pieces
    // while they stay within kNearMargin - 1 cells of it.
    constexpr I64 kNearMargin = 4;
    for (std::uint32_t k = 0; k < edges_.size(); ++k) {
      const InputEdge& e = edges_[k];
      if (far_and_dropped(e, op)) continue;
      gather_near(e.cp, e.cq, kNearMargin, edge_near_);
      if (edge_near_.empty()) continue;
      hot_pixels_on(e.p, e.q, e.cp, e.cq, edge_near_);
      if (found_.empty()) continue;
      // The edge's own ends are hot too, and a bent piece may pass them.
      edge_near_.push_back(e.cp);
      edge_near_.push_back(e.cq);
      path_.clear();
      path_.push_back(e.cp);
      path_.insert(path_.end(), found_.begin(), found_.end());
      path_.push_back(e.cq);
      const I64 min_x = e.min_x - (kNearMargin - 1), max_x = e.max_x + (kNearMargin - 1);
      const I64 min_y = e.min_y - (kNearMargin - 1), max_y = e.max_y + (kNearMargin - 1);
      auto within = [&](const IPoint& c) { return c.x >= min_x && c.x <= max_x && c.y >= min_y && c.y <= max_y; };
      // Each round adds hot pixels near the edge and there are finitely
      // many; the bound only stops a loop that would be a bug.
      for (bool bent = true; bent && path_.size() <= hot_.size() + 2;) {
        bent = false;
        for (std::size_t i = 0; i + 1 < path_.size(); ++i) {
          const IPoint& u = path_[i];
          const IPoint& v = path_[i + 1];
          const bool near_edge = within(u) && within(v);
          if (!near_edge) gather_near(u, v, 1, piece_near_);
          hot_pixels_on(fine_of(u), fine_of(v), u, v, near_edge ? edge_near_ : piece_near_);
          if (found_.empty()) continue;
          path_.insert(path_.begin() + static_cast<std::ptrdiff_t>(i) + 1, found_.begin(), found_.end());
          i += found_.size();
          bent = true;
        }
      }
      for (std::size_t i = 1; i + 1 < path_.size(); ++i) bends_.push_back({k, path_[i]});
    }
  }

  // The id of the vertex at p: one id for one point, also where an operand
  // touches itself (two of its rings at one point: a union can join them
  // into one ring, which must then split there).
  std::uint32_t vertex(const IPoint& p, std::uint8_t side) {
    std::uint64_t slot = hash_of(p) & vertex_mask_;
    for (;; slot = (slot + 1) & vertex_mask_) {
      const std::uint32_t id = vertex_table_[slot];
      if (id == kNone) break;
      if (vertices_[id] == p) {
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
    // bends_ is in edge order already, and in path order within an edge
    // (bend_edges appends a whole path at a time).
    std::size_t slots = 16;
    while (slots < 2 * (edges_.size() + bends_.size())) slots *= 2;
    vertex_table_.assign(slots, kNone);
    vertex_mask_ = slots - 1;
    vertices_.reserve(edges_.size() + bends_.size());
    vertex_sides_.reserve(edges_.size() + bends_.size());
    pieces_.reserve(edges_.size() + bends_.size());
    std::size_t s = 0;
    for (auto& ring : rings_) {
      ring.first_piece = static_cast<std::uint32_t>(pieces_.size());
      const std::uint32_t ring_start = vertex(edges_[ring.first_edge].cp, ring.side);
      std::uint32_t from = ring_start;
      // An edge within a cell, or a bend back through its start's cell,
      // makes no piece.
      auto add_piece = [&](std::uint32_t to, const InputEdge& e) {
        if (to != from) pieces_.push_back({from, to, e.type, e.side});
        from = to;
      };
      for (std::uint32_t k = ring.first_edge; k < ring.last_edge; ++k) {
        const InputEdge& e = edges_[k];
        while (s < bends_.size() && bends_[s].edge < k) ++s;
        for (; s < bends_.size() && bends_[s].edge == k; ++s) add_piece(vertex(bends_[s].at, e.side), e);
        // The ring's edges are consecutive and closed: e.q starts the next.
        add_piece(k + 1 < ring.last_edge ? vertex(e.cq, e.side) : ring_start, e);
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

  // Pieces with the same end points. After snap rounding, pieces meet only
  // at their ends or along whole pieces, so these are all the overlaps:
  // - of one side in opposite directions: a sliver thinner than a cell,
  //   collapsed; both copies are dropped;
  // - of a and b: kept once where they bound the result.
  void mark_coincident() {
    for (std::uint32_t k = 0; k < pieces_.size(); ++k) {
      Piece& p = pieces_[k];
      if (p.coincident != 0) continue;
      for (std::uint32_t m = incident_start_[p.from]; m < incident_start_[p.from + 1]; ++m) {
        Piece& twin = pieces_[incident_[m]];
        if (incident_[m] == k || twin.coincident != 0 || twin.side != p.side) continue;
        if (twin.from == p.to && twin.to == p.from) {
          twin.coincident = p.coincident = 2;
          break;
        }
      }
    }
    for (auto& p : pieces_) {
      if (p.side != 1 || p.coincident != 0 || !(vertex_sides_[p.from] & vertex_sides_[p.to] & 1u)) continue;
      for (std::uint32_t m = incident_start_[p.from]; m < incident_start_[p.from + 1]; ++m) {
        Piece& twin = pieces_[incident_[m]];
        if (twin.side != 0 || twin.coincident != 0) continue;
        const bool same = twin.from == p.from && twin.to == p.to;
        if (!same && !(twin.from == p.to && twin.to == p.from)) continue;
        twin.coincident = p.coincident = same ? 1 : -1;
        twin.type = std::min(twin.type, p.type);  // used if a's piece is kept
        break;
      }
    }
  }

  // Whether the point (x2 / 2, y2 / 2) (doubled units: the midpoint of a
  // piece) is inside `side`, by even-odd over its pieces (its rings do not
  // cross, so a point is inside the multi-polygon when it is inside an odd
  // number of them). The point lies on no piece of that side: a piece
  // through it would be its piece's twin. The pieces are listed by
  // horizontal slab (built on the first test of a side), so a test reads
  // only the pieces of its slab: rings that meet the other side nowhere
  // take one test each, and merging a whole map has hundreds of them.
  bool inside(I64 x2, I64 y2, std::uint8_t side) {
    Slabs& slabs = slabs_[side];
    if (!slabs.built) build_slabs(side);
    if (slabs.start.empty() || y2 < 2 * slabs.min_y || y2 > 2 * slabs.max_y) return false;
    const auto rows = static_cast<int>(slabs.start.size() - 1);
    const int r = static_cast<int>(std::clamp<I64>((y2 / 2 - slabs.min_y) / slabs.height, 0, rows - 1));
    bool in = false;
    for (std::uint32_t j = slabs.start[static_cast<std::size_t>(r)]; j < slabs.start[static_cast<std::size_t>(r) + 1];
         ++j) {
      const Piece& piece = pieces_[slabs.pieces[j]];
      if (crosses_ray(vertices_[piece.from], vertices_[piece.to], x2, y2)) in = !in;
    }
    return in;
  }

  void build_slabs(std::uint8_t side) {
    Slabs& slabs = slabs_[side];
    slabs.built = true;
    slabs.start.clear();
    slabs.pieces.clear();
    I64 lo = std::numeric_limits<I64>::max(), hi = std::numeric_limits<I64>::min();
    std::size_t count = 0;
    for (const auto& p : pieces_)
      if (p.side == side && p.coincident != 2) {
        lo = std::min({lo, vertices_[p.from].y, vertices_[p.to].y});
        hi = std::max({hi, vertices_[p.from].y, vertices_[p.to].y});
        ++count;
      }
    if (count == 0) return;
    const int rows = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(count))), 1, 256);
    slabs.min_y = lo;
    slabs.max_y = hi;
    slabs.height = std::max<I64>((hi - lo) / rows + 1, 1);
    auto row_of = [&](I64 y) { return static_cast<int>(std::clamp<I64>((y - lo) / slabs.height, 0, rows - 1)); };
    build_lists(static_cast<std::size_t>(rows), slabs.start, slabs.pieces, fill_, [&](auto&& emit) {
      for (std::uint32_t k = 0; k < pieces_.size(); ++k) {
        const Piece& p = pieces_[k];
        if (p.side != side || p.coincident == 2) continue;
        const I64 y0 = vertices_[p.from].y, y1 = vertices_[p.to].y;
        for (int r = row_of(std::min(y0, y1)); r <= row_of(std::max(y0, y1)); ++r) emit(static_cast<std::size_t>(r), k);
      }
    });
  }

  // Whether piece p, leaving a vertex the other side's boundary passes
  // through, enters the other side, read off the other side's pieces at that
  // vertex: the other side's interior is on the left of its pieces, so what
  // lies just counter-clockwise of a piece leaving the vertex is inside and
  // what lies just counter-clockwise of a piece arriving is outside. The
  // first of them clockwise from p decides. nullopt: no piece of the other
  // side is there but collapsed slivers (a point-in-polygon test decides).
  std::optional<bool> enters_other_side(const Piece& p) const {
    const std::uint32_t v = p.from;
    const IPoint& at = vertices_[v];
    const IPoint d = vertices_[p.to] - at;
    // The other side's direction nearest clockwise from p = the one from
    // which p is reached first turning counter-clockwise: the largest
    // counter-clockwise angle from d to it.
    bool found = false, best_leaves = false;
    IPoint best;
    for (std::uint32_t m = incident_start_[v]; m < incident_start_[v + 1]; ++m) {
      const Piece& q = pieces_[incident_[m]];
      if (q.side == p.side || q.coincident == 2) continue;
      const bool leaves = q.from == v;
      const IPoint e = vertices_[leaves ? q.to : q.from] - at;
      // Same direction as p: a coincident piece, which classify does not ask about.
      if (!found || turns_before(d, best, e)) {
        best = e;
        best_leaves = leaves;
        found = true;
      }
    }
    if (!found) return std::nullopt;
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
          known = false;  // the next piece can start where the other side's boundary passes
          if (p.coincident == 2) continue;  // keep stays false

          // One copy (a's) where the piece bounds the result: same direction
          // for union and intersection, opposite for the difference.
          p.keep = p.side == 0 && (p.coincident > 0) == (op != OverlayOp::kDifference);
          continue;
        }
        if (!known || (vertex_sides_[p.from] & (1u << other))) {
          std::optional<bool> enters;
          if (vertex_sides_[p.from] & (1u << other)) enters = enters_other_side(p);
          if (!enters) {
            const IPoint& u = vertices_[p.from];
            const IPoint& v = vertices_[p.to];
            enters = inside(u.x + v.x, u.y + v.y, other);
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

    // The way on from piece k: the first kept piece clockwise from the way
    // back, i.e. the largest counter-clockwise angle from the way back.
    auto next_of = [&](std::uint32_t k) -> std::uint32_t {
      const std::uint32_t v = pieces_[k].to;
      const std::uint32_t b = out_start_[v], e = out_start_[v + 1];
      if (e == b) return kNone;
      if (e == b + 1) return out_[b];
      const IPoint& at = vertices_[v];
      const IPoint back = vertices_[pieces_[k].from] - at;
      std::uint32_t best = out_[b];
      IPoint best_d = vertices_[pieces_[best].to] - at;
      for (std::uint32_t m = b + 1; m < e; ++m) {
        const IPoint d = vertices_[pieces_[out_[m]].to] - at;
        if (turns_before(back, best_d, d)) {
          best = out_[m];
          best_d = d;
        }
      }
      return best;
    };

    // The border box's sides on the grid, as the pieces' coordinates are.
    std::optional<IPoint> box_lo, box_hi;
    if (border_box) {
      IPoint lo, hi;
      if (to_fine(border_box->min_corner(), lo) && to_fine(border_box->max_corner(), hi))
        box_lo = cell_of(lo), box_hi = cell_of(hi);
    }
    auto on_box_side = [&](const IPoint& a, const IPoint& b) {
      return (a.x == box_lo->x && b.x == box_lo->x) || (a.x == box_hi->x && b.x == box_hi->x) ||
             (a.y == box_lo->y && b.y == box_lo->y) || (a.y == box_hi->y && b.y == box_hi->y);
    };

    used_.assign(pieces_.size(), 0);
    position_.assign(nv, -1);
    std::vector<TypedRing> holes;
    outer_loops_.clear();
    hole_loops_.clear();
    loop_pieces_.clear();
    // One closed loop of pieces: a polygon (counter-clockwise) or a hole;
    // none if it encloses no area (it cannot, but for collapsed slivers).
    auto emit = [&](std::span<const std::uint32_t> loop) {
      if (loop.size() < 3) return;
      I128 twice_area = 0;
      for (const std::uint32_t piece : loop)
        twice_area += cross(vertices_[pieces_[piece].from], vertices_[pieces_[piece].to]);
      if (twice_area == 0) return;
      TypedRing ring;
      ring.ring.reserve(loop.size() + 1);
      ring.types.reserve(loop.size());
      for (const std::uint32_t piece : loop) {
        const Piece& p = pieces_[piece];
        ring.ring.push_back(to_point(vertices_[p.from]));
        ring.types.push_back(box_lo && on_box_side(vertices_[p.from], vertices_[p.to]) ? EdgeType::kBorder : p.type);
      }
      ring.ring.push_back(ring.ring.front());
      const auto first_piece = static_cast<std::uint32_t>(loop_pieces_.size());
      const auto size = static_cast<std::uint32_t>(loop.size());
      if (twice_area > 0) {
        TypedPolygon polygon;
        polygon.geometry.outer() = std::move(ring.ring);
        polygon.edge_types.push_back(std::move(ring.types));
        result.polygons.push_back(std::move(polygon));
        outer_loops_.push_back(Loop{first_piece, size, twice_area});
      } else {
        holes.push_back(std::move(ring));
        hole_loops_.push_back(Loop{first_piece, size, twice_area});
      }
      loop_pieces_.insert(loop_pieces_.end(), loop.begin(), loop.end());
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
          // Cannot happen for valid operands (the pieces form a planar
          // arrangement and each kept one has a kept way on); for operands
          // that were not valid, said rather than guessed.
          result.error = "overlay: pieces do not link into rings (an operand is not valid)";
          return result;
        }
        k = next;
      }
      // The sharpest left turn keeps polygons that touch at a point apart, but
      // joins holes that touch at a point (and a hole touching its outer
      // ring) into one ring through that point twice, which OGC forbids: such
      // a ring is cut into its loops at every repeated vertex.
      loop_.clear();
      for (const std::uint32_t piece : ring_pieces_) {
        const std::uint32_t v = pieces_[piece].from;
        if (position_[v] >= 0) {
          const auto at = static_cast<std::size_t>(position_[v]);
          emit(std::span(loop_).subspan(at));
          for (std::size_t j = at; j < loop_.size(); ++j) position_[pieces_[loop_[j]].from] = -1;
          loop_.resize(at);
        }
        position_[v] = static_cast<std::int32_t>(loop_.size());
        loop_.push_back(piece);
      }
      emit(loop_);
      for (const std::uint32_t piece : loop_) position_[pieces_[piece].from] = -1;
    }
    for (std::size_t h = 0; h < holes.size(); ++h) {
      const std::size_t home = home_of(hole_loops_[h]);
      if (home == kNone) {
        // Cannot happen for valid operands: every hole of the result lies in
        // one of its polygons.
        result.error = "overlay: a hole with no polygon around it (an operand is not valid)";
        result.polygons.clear();
        return result;
      }
      result.polygons[home].geometry.inners().push_back(std::move(holes[h].ring));
      result.polygons[home].edge_types.push_back(std::move(holes[h].types));
    }
    result.ok = true;
    return result;
  }

  // The polygon a hole belongs to: the one of least area whose outer ring
  // has the midpoint of the hole's first piece inside. Exact: that point
  // (half units) lies on no other kept piece, since kept pieces meet only
  // at their ends. kNone if none has.
  std::size_t home_of(const Loop& hole) const {
    const Piece& first = pieces_[loop_pieces_[hole.first]];
    const IPoint& u = vertices_[first.from];
    const IPoint& v = vertices_[first.to];
    const I64 x2 = u.x + v.x, y2 = u.y + v.y;
    std::size_t home = kNone;
    for (std::size_t k = 0; k < outer_loops_.size(); ++k) {
      const Loop& outer = outer_loops_[k];
      if (home != kNone && outer.twice_area >= outer_loops_[home].twice_area) continue;
      bool in = false;
      for (std::uint32_t j = outer.first; j < outer.first + outer.size; ++j) {
        const Piece& piece = pieces_[loop_pieces_[j]];
        if (crosses_ray(vertices_[piece.from], vertices_[piece.to], x2, y2)) in = !in;
      }
      if (in) home = k;
    }
    return home;
  }
};

}  // namespace

double to_overlay_grid(double v) {
  IPoint fine;
  if (!to_fine(Point(v, 0.0), fine)) return v;
  return static_cast<double>(cell_of(fine).x) / kGridScale;
}

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
