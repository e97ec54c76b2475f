#include "planning/inward_offset.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <unordered_map>
#include <vector>

#include <polyclipping/clipper.hpp>

#include "mapping/edge_reassignment.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

namespace bg = boost::geometry;
using ClipperLib::cInt;
using ClipperLib::IntPoint;
using ClipperLib::Path;
using ClipperLib::Paths;

namespace {

// Clipper works on integers: 10 um units keep map coordinates up to 10 km in
// its fast 64-bit range (|c| < 2^30) and round far below the C-space's
// interior_offset_m.
constexpr double kUnitsPerM = 1e5;
// Coordinates beyond this are refused: in grid units, with a tile's growth
// and the products of the clipping, they stay far inside 64 bits and
// Clipper's range (4.6e18).
constexpr double kMaxAbsCoordinateM = 1e9;
// The input of a tile is the polygon clipped to the tile grown by the offset
// distance and this slack (more than the joins' chord error): the erosion of
// that covers the erosion of the whole polygon within the tile and a little
// beyond (so the results of neighbouring tiles overlap, and their union
// joins them whatever the rounding), and nowhere more than it (an erosion
// of less is less).
constexpr cInt kInputSlack = 1000;  // 1 cm
// At most this many tiles over one polygon's box; a larger box (coordinates
// far beyond a building) is offset whole.
constexpr long long kMaxTiles = 1 << 16;
// A map's edges are short beside a tile, so each is listed in a few tiles'
// keys. A polygon whose edges would be listed more than this many times per
// vertex on average (long edges across many tiles: a map nothing like a
// building's, or hostile) is offset whole, so the keys' size stays bounded.
constexpr long double kMaxTilesPerEdge = 32;
// InwardOffset::simplify_epsilon_m on a tiled polygon: its tiles are
// simplified by the epsilon less this, and the union by this (at most half
// the epsilon). The union's own vertices are where the tiles' results cross
// (within a grid unit of a tile's boundary: nearly collinear, and the turn
// a unit's rounding gives them would make them reflex nodes).
constexpr double kSeamEpsilonM = 5e-4;

// Finite and within kMaxAbsCoordinateM: on Clipper's grid.
bool on_grid(const mapping::Point& p) {
  return std::abs(p.x()) <= kMaxAbsCoordinateM && std::abs(p.y()) <= kMaxAbsCoordinateM;
}

bool on_grid(const mapping::Ring& ring) {
  return std::all_of(ring.begin(), ring.end(), [](const mapping::Point& p) { return on_grid(p); });
}

bool on_grid(const mapping::Polygon& polygon) {
  return on_grid(polygon.outer()) &&
         std::all_of(polygon.inners().begin(), polygon.inners().end(), [](const auto& r) { return on_grid(r); });
}

bool on_grid(const mapping::MultiPolygon& polygons) {
  return std::all_of(polygons.begin(), polygons.end(), [](const mapping::Polygon& p) { return on_grid(p); });
}

Path to_clipper(const mapping::Ring& ring) {
  Path path;
  path.reserve(ring.size());
  for (std::size_t i = 0; i + 1 < ring.size(); ++i)  // closed ring: the last point repeats the first
    path.emplace_back(static_cast<cInt>(std::llround(ring[i].x() * kUnitsPerM)),
                      static_cast<cInt>(std::llround(ring[i].y() * kUnitsPerM)));
  return path;
}

mapping::Ring from_clipper(const Path& path) {
  mapping::Ring ring;
  ring.reserve(path.size() + 1);
  for (const auto& q : path)
    ring.emplace_back(static_cast<double>(q.X) / kUnitsPerM, static_cast<double>(q.Y) / kUnitsPerM);
  if (!ring.empty()) ring.push_back(ring.front());
  return ring;
}

// Clipper's tree nests outer rings and holes: each outer node with its hole
// children is a polygon; an outer node inside a hole is a polygon of its own.
void append_polygons(const ClipperLib::PolyTree& tree, mapping::MultiPolygon& out) {
  std::vector<const ClipperLib::PolyNode*> outers(tree.Childs.begin(), tree.Childs.end());
  for (std::size_t k = 0; k < outers.size(); ++k) {
    const ClipperLib::PolyNode* outer = outers[k];
    mapping::Polygon polygon;
    polygon.outer() = from_clipper(outer->Contour);
    for (const ClipperLib::PolyNode* hole : outer->Childs) {
      polygon.inners().push_back(from_clipper(hole->Contour));
      for (const ClipperLib::PolyNode* inner : hole->Childs) outers.push_back(inner);
    }
    // Clipper's orientation (positive area for outer rings) is ours in a
    // y-up frame; correct() only closes and orders what needs it.
    bg::correct(polygon);
    out.push_back(std::move(polygon));
  }
}

void add_rings(const mapping::MultiPolygon& polygons, ClipperLib::PolyType type, ClipperLib::Clipper& clipper) {
  for (const auto& polygon : polygons) {
    Paths rings{to_clipper(polygon.outer())};
    for (const auto& hole : polygon.inners()) rings.push_back(to_clipper(hole));
    std::erase_if(rings, [](const Path& ring) { return ring.size() < 3; });
    clipper.AddPaths(rings, type, true);
  }
}

struct IntBox {
  cInt x0, y0, x1, y1;
  IntBox grown(cInt d) const { return {x0 - d, y0 - d, x1 + d, y1 + d}; }
  bool meets(const IntBox& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
  bool holds(const IntBox& o) const { return x0 <= o.x0 && o.x1 <= x1 && y0 <= o.y0 && o.y1 <= y1; }
  Path ring() const { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }  // counter-clockwise
};

IntBox box_of(const Path& path) {
  IntBox b{path[0].X, path[0].Y, path[0].X, path[0].Y};
  for (const auto& p : path) {
    b.x0 = std::min(b.x0, p.X);
    b.y0 = std::min(b.y0, p.Y);
    b.x1 = std::max(b.x1, p.X);
    b.y1 = std::max(b.y1, p.Y);
  }
  return b;
}

// floor(a / b) for b > 0.
cInt floor_div(cInt a, cInt b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Sutherland-Hodgman: the ring clipped to the box, in the ring's
// orientation. Where the ring leaves the box and comes back, the result runs
// along the box's side (zero-width bridges): they lie on the box's boundary,
// which is farther than the offset distance from what the tile keeps.
Path clip_to_box(const Path& ring, const IntBox& box) {
  Path in = ring, out;
  // side 0..3: x >= x0, x <= x1, y >= y0, y <= y1
  for (int side = 0; side < 4 && !in.empty(); ++side) {
    auto inside = [&](const IntPoint& p) {
      switch (side) {
        case 0: return p.X >= box.x0;
        case 1: return p.X <= box.x1;
        case 2: return p.Y >= box.y0;
        default: return p.Y <= box.y1;
      }
    };
    // Where p-q crosses the side's line, rounded to the grid (long double:
    // the product of two coordinate differences is exact).
    auto crossing = [&](const IntPoint& p, const IntPoint& q) {
      if (side < 2) {
        const cInt x = side == 0 ? box.x0 : box.x1;
        const long double t = static_cast<long double>(x - p.X) / static_cast<long double>(q.X - p.X);
        return IntPoint(x, p.Y + static_cast<cInt>(std::llround(t * static_cast<long double>(q.Y - p.Y))));
      }
      const cInt y = side == 2 ? box.y0 : box.y1;
      const long double t = static_cast<long double>(y - p.Y) / static_cast<long double>(q.Y - p.Y);
      return IntPoint(p.X + static_cast<cInt>(std::llround(t * static_cast<long double>(q.X - p.X))), y);
    };
    out.clear();
    for (std::size_t i = 0; i < in.size(); ++i) {
      const IntPoint& p = in[i];
      const IntPoint& q = in[(i + 1) % in.size()];
      const bool p_in = inside(p), q_in = inside(q);
      if (p_in) out.push_back(p);
      if (p_in != q_in) out.push_back(crossing(p, q));
    }
    std::swap(in, out);
  }
  return in;
}

// Paths (outer ring first: Clipper's offset takes the orientation of the
// path with the lowest vertex as that of outer rings) shrunk by delta.
// Out: Paths, or a PolyTree (the rings nested as polygons).
template <class Out>
void erode(const Paths& paths, double delta, double arc_tolerance, Out& out) {
  ClipperLib::ClipperOffset offset;
  offset.ArcTolerance = arc_tolerance;
  offset.AddPaths(paths, ClipperLib::jtRound, ClipperLib::etClosedPolygon);
  offset.Execute(out, -delta);
}

// fn(a, b) for every edge of the rings (closed: the last vertex to the first).
template <class Fn>
void for_each_edge(const Paths& rings, Fn&& fn) {
  for (const auto& r : rings)
    for (std::size_t k = 0; k < r.size(); ++k) fn(r[k], r[(k + 1) % r.size()]);
}

std::uint64_t hash_of(const std::vector<cInt>& key) {
  std::uint64_t h = 0x9e3779b97f4a7c15ull;
  for (const cInt v : key) {
    std::uint64_t x = static_cast<std::uint64_t>(v) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    x ^= x >> 31;
    x *= 0xbf58476d1ce4e5b9ull;
    h ^= x ^ (x >> 29);
  }
  return h;
}

// The offset's parameters, the head of every key.
std::vector<cInt> key_head(cInt tag, cInt delta, double arc_tolerance) {
  return {tag, delta, std::bit_cast<cInt>(arc_tolerance)};
}

}  // namespace

struct OffsetTileCache::Impl {
  struct Entry {
    std::vector<cInt> key;
    Paths tile;                     // a tile's result
    mapping::MultiPolygon polygon;  // a whole polygon's result
    std::int64_t last_call = 0;
  };
  std::unordered_map<std::uint64_t, std::vector<Entry>> table;
  std::int64_t call = 0;

  Entry* find(std::uint64_t hash, const std::vector<cInt>& key) {
    auto it = table.find(hash);
    if (it == table.end()) return nullptr;
    for (Entry& e : it->second)
      if (e.key == key) {
        e.last_call = call;
        return &e;
      }
    return nullptr;
  }
  Entry& add(std::uint64_t hash, std::vector<cInt> key) {
    auto& bucket = table[hash];
    bucket.push_back(Entry{std::move(key), {}, {}, call});
    return bucket.back();
  }
  void drop_old() {
    for (auto it = table.begin(); it != table.end();) {
      auto& bucket = it->second;
      std::erase_if(bucket, [&](const Entry& e) { return e.last_call + kKeptCalls <= call; });
      it = bucket.empty() ? table.erase(it) : std::next(it);
    }
  }
};

OffsetTileCache::OffsetTileCache() : impl_(std::make_unique<Impl>()) {}
OffsetTileCache::~OffsetTileCache() = default;
std::size_t OffsetTileCache::entries() const {
  std::size_t n = 0;
  for (const auto& [hash, bucket] : impl_->table) n += bucket.size();
  return n;
}

namespace {

__extension__ typedef __int128 I128;  // GCC and Clang; -Wpedantic knows no 128-bit type

// 2 x the signed area of triangle (a, b, c), exact: grid coordinates are
// below 2^47 (kMaxAbsCoordinateM and a tile's growth), their products far
// below 2^127.
I128 orientation(const IntPoint& a, const IntPoint& b, const IntPoint& c) {
  return I128(b.X - a.X) * (c.Y - a.Y) - I128(b.Y - a.Y) * (c.X - a.X);
}

int sign(I128 v) { return (v > 0) - (v < 0); }

bool on_segment(const IntPoint& a, const IntPoint& b, const IntPoint& p) {
  return std::min(a.X, b.X) <= p.X && p.X <= std::max(a.X, b.X) && std::min(a.Y, b.Y) <= p.Y &&
         p.Y <= std::max(a.Y, b.Y);
}

// Whether the closed segments a-b and c-d meet.
bool segments_meet(const IntPoint& a, const IntPoint& b, const IntPoint& c, const IntPoint& d) {
  const int o1 = sign(orientation(a, b, c)), o2 = sign(orientation(a, b, d));
  const int o3 = sign(orientation(c, d, a)), o4 = sign(orientation(c, d, b));
  if (o1 != o2 && o3 != o4) return true;
  return (o1 == 0 && on_segment(a, b, c)) || (o2 == 0 && on_segment(a, b, d)) ||
         (o3 == 0 && on_segment(c, d, a)) || (o4 == 0 && on_segment(c, d, b));
}

// Whether two edges of the rings meet anywhere but at the vertex two
// neighbours of one ring share: a sweep over the edges by x. Rings of long
// edges side by side (nothing like a building's, or hostile) would make
// that quadratic: past kMeetTestsPerEdge pairs per edge it answers true
// (not shown apart), and the caller keeps what it had.
constexpr std::size_t kMeetTestsPerEdge = 64;
bool rings_meet(const Paths& rings) {
  struct E {
    cInt x0, x1;
    std::uint32_t ring, k;
  };
  std::vector<E> edges;
  for (std::uint32_t r = 0; r < rings.size(); ++r)
    for (std::uint32_t k = 0; k < rings[r].size(); ++k) {
      const IntPoint& a = rings[r][k];
      const IntPoint& b = rings[r][(k + 1) % rings[r].size()];
      edges.push_back({std::min(a.X, b.X), std::max(a.X, b.X), r, k});
    }
  std::sort(edges.begin(), edges.end(), [](const E& a, const E& b) { return a.x0 < b.x0; });
  std::size_t budget = kMeetTestsPerEdge * edges.size();
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const E& e = edges[i];
    const Path& re = rings[e.ring];
    const IntPoint& a = re[e.k];
    const IntPoint& b = re[(e.k + 1) % re.size()];
    for (std::size_t j = i + 1; j < edges.size() && edges[j].x0 <= e.x1; ++j) {
      if (budget-- == 0) return true;
      const E& f = edges[j];
      const Path& rf = rings[f.ring];
      const IntPoint& c = rf[f.k];
      const IntPoint& d = rf[(f.k + 1) % rf.size()];
      if (f.ring == e.ring) {
        const std::size_t n = re.size();
        // Neighbours share one vertex: they meet elsewhere only if they overlap.
        if ((e.k + 1) % n == f.k) {
          if (sign(orientation(a, b, d)) == 0 && on_segment(a, b, d)) return true;
          if (sign(orientation(c, d, a)) == 0 && on_segment(c, d, a)) return true;
          continue;
        }
        if ((f.k + 1) % n == e.k) {
          if (sign(orientation(c, d, b)) == 0 && on_segment(c, d, b)) return true;
          if (sign(orientation(a, b, c)) == 0 && on_segment(a, b, c)) return true;
          continue;
        }
      }
      if (segments_meet(a, b, c, d)) return true;
    }
  }
  return false;
}

// RDP on a closed ring, every vertex `fixed` says kept. Empty: nothing to
// keep it from (fewer than 3 vertices left, no area, or turned over).
template <class Fixed>
Path simplified_ring(const Path& ring, double epsilon_units, Fixed fixed) {
  const std::size_t n = ring.size();
  std::size_t start = 0;  // the first vertex fixed, or 0
  while (start < n && !fixed(ring[start])) ++start;
  if (start == n) start = 0;
  // Scratch kept per thread, as simplify_typed's.
  thread_local std::vector<mapping::Point> points;
  thread_local std::vector<bool> keep;
  points.resize(n + 1);
  keep.assign(n + 1, false);
  for (std::size_t i = 0; i <= n; ++i) {
    const IntPoint& q = ring[(start + i) % n];
    points[i] = mapping::Point(static_cast<double>(q.X), static_cast<double>(q.Y));
    keep[i] = i == 0 || i == n || fixed(q);
  }
  mapping::rdp_keep_ring(points, epsilon_units, keep);
  Path out;
  for (std::size_t i = 0; i < n; ++i)
    if (keep[i]) out.push_back(ring[(start + i) % n]);
  const double area = out.size() >= 3 ? ClipperLib::Area(out) : 0.0;
  if (area == 0.0 || (area > 0.0) != (ClipperLib::Area(ring) > 0.0)) return {};
  return out;
}

struct Eroder {
  cInt delta = 0;
  double arc_tolerance = 0.0;
  cInt largest_tile = 0;  // 0: no tiles
  cInt tile = 0;          // the tiles of the polygon being offset
  int tile_min_vertices = 0;
  double tile_epsilon = 0.0;  // a tile's simplification, in grid units (0: none)
  OffsetTileCache::Impl* cache = nullptr;
  OffsetTileCache::Counters* counters = nullptr;

  // One polygon's rings, the outer ring first. True: offset in tiles.
  bool polygon(const Paths& rings, mapping::MultiPolygon& out) {
    std::size_t vertices = 0;
    for (const auto& r : rings) vertices += r.size();
    const IntBox box = box_of(rings[0]);
    // Tiles of about tile_min_vertices vertices, halving the largest side
    // up to twice while the polygon's box is denser than that: a ragged map
    // (a real building, scanned: 3-15 vertices per m^2) puts a thousand or
    // more in a 12 m tile, and the live view opens the tiles about the
    // robot afresh every plan (intel, fr079: a smaller tile 10-15 % less
    // CPU per plan); a sparse map (campus) keeps its large tiles, whose
    // seams would cost more than their offsets.
    tile = largest_tile;
    const long double area = static_cast<long double>(box.x1 - box.x0) * static_cast<long double>(box.y1 - box.y0);
    for (int halved = 0; halved < 2 && tile > 0 && tile_min_vertices > 0 && area > 0 && tile / 2 >= delta &&
                         static_cast<long double>(tile) * static_cast<long double>(tile) *
                                 static_cast<long double>(vertices) / area >
                             static_cast<long double>(tile_min_vertices);
         ++halved)
      tile /= 2;
    if (tile > 0 && vertices >= static_cast<std::size_t>(tile_min_vertices) && tiles_over(box) <= kMaxTiles &&
        edge_listings(rings) <= kMaxTilesPerEdge * static_cast<long double>(vertices)) {
      tiled(rings, box, out);
      return true;
    }
    whole(rings, out);
    return false;
  }

  // How far a tile's input box reaches beyond the tile.
  cInt input_reach() const { return delta + kInputSlack; }
  // The edge's box grown by that reach: the tiles it meets list the edge.
  IntBox reach_of(const IntPoint& a, const IntPoint& b) const {
    return IntBox{std::min(a.X, b.X), std::min(a.Y, b.Y), std::max(a.X, b.X), std::max(a.Y, b.Y)}.grown(input_reach());
  }
  // How many tile keys would list the rings' edges.
  long double edge_listings(const Paths& rings) const {
    long double n = 0;
    for_each_edge(rings, [&](const IntPoint& a, const IntPoint& b) {
      const IntBox e = reach_of(a, b);
      n += static_cast<long double>(floor_div(e.x1, tile) - floor_div(e.x0, tile) + 1) *
           static_cast<long double>(floor_div(e.y1, tile) - floor_div(e.y0, tile) + 1);
    });
    return n;
  }

  long long tiles_over(const IntBox& b) const {
    const long double nx = static_cast<long double>(b.x1 - b.x0) / static_cast<long double>(tile) + 3;
    const long double ny = static_cast<long double>(b.y1 - b.y0) / static_cast<long double>(tile) + 3;
    return nx * ny > static_cast<long double>(kMaxTiles) ? kMaxTiles + 1 : static_cast<long long>(nx * ny);
  }

  void whole(const Paths& rings, mapping::MultiPolygon& out) {
    std::vector<cInt> key;
    std::uint64_t hash = 0;
    if (cache) {
      key = key_head(0, delta, arc_tolerance);
      for (const auto& r : rings) {
        key.push_back(static_cast<cInt>(r.size()));
        for (const auto& p : r) {
          key.push_back(p.X);
          key.push_back(p.Y);
        }
      }
      hash = hash_of(key);
      if (const auto* e = cache->find(hash, key)) {
        ++counters->hits;
        out.insert(out.end(), e->polygon.begin(), e->polygon.end());
        return;
      }
    }
    ClipperLib::PolyTree tree;
    erode(rings, static_cast<double>(delta), arc_tolerance, tree);
    const std::size_t first = out.size();
    append_polygons(tree, out);
    if (cache) {
      ++counters->misses;
      cache->add(hash, std::move(key)).polygon.assign(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
    }
  }

  // The polygon's erosion within each tile it reaches, united.
  void tiled(const Paths& rings, const IntBox& box, mapping::MultiPolygon& out) {
    // The tiles that meet the polygon's box.
    const cInt i0 = floor_div(box.x0, tile), i1 = floor_div(box.x1, tile);
    const cInt j0 = floor_div(box.y0, tile), j1 = floor_div(box.y1, tile);
    const auto nx = static_cast<std::size_t>(i1 - i0 + 1), ny = static_cast<std::size_t>(j1 - j0 + 1);
    auto tile_box = [&](std::size_t ix, std::size_t iy) {
      const cInt x = (i0 + static_cast<cInt>(ix)) * tile, y = (j0 + static_cast<cInt>(iy)) * tile;
      return IntBox{x, y, x + tile, y + tile};
    };

    // Each tile's key: every directed edge whose box meets the tile's input
    // box (a superset of those that cross it), in ring order.
    std::vector<std::vector<cInt>> edges(nx * ny);
    for_each_edge(rings, [&](const IntPoint& a, const IntPoint& b) {
      const IntBox e = reach_of(a, b);
      const cInt tx0 = std::max(i0, floor_div(e.x0, tile)), tx1 = std::min(i1, floor_div(e.x1, tile));
      const cInt ty0 = std::max(j0, floor_div(e.y0, tile)), ty1 = std::min(j1, floor_div(e.y1, tile));
      for (cInt ty = ty0; ty <= ty1; ++ty)
        for (cInt tx = tx0; tx <= tx1; ++tx) {
          auto& listed = edges[static_cast<std::size_t>(ty - j0) * nx + static_cast<std::size_t>(tx - i0)];
          listed.insert(listed.end(), {a.X, a.Y, b.X, b.Y});
        }
    });
    // Whether each tile's centre is inside the polygon (non-zero winding):
    // with the edges, this fixes the polygon within the tile's input box
    // (a box no edge meets is all inside or all outside).
    std::vector<char> inside(nx * ny, 0);
    std::vector<std::pair<cInt, int>> crossings;  // x, +1 upward / -1 downward
    for (std::size_t iy = 0; iy < ny; ++iy) {
      const cInt cy = (j0 + static_cast<cInt>(iy)) * tile + tile / 2;
      crossings.clear();
      for_each_edge(rings, [&](const IntPoint& a, const IntPoint& b) {
        const bool up = a.Y <= cy && cy < b.Y, down = b.Y <= cy && cy < a.Y;
        if (!up && !down) return;
        const long double t = static_cast<long double>(cy - a.Y) / static_cast<long double>(b.Y - a.Y);
        const long double x = static_cast<long double>(a.X) + t * static_cast<long double>(b.X - a.X);
        crossings.emplace_back(static_cast<cInt>(std::floor(x)), up ? 1 : -1);
      });
      std::sort(crossings.begin(), crossings.end());
      std::size_t next = 0;
      int winding = 0;
      for (std::size_t ix = 0; ix < nx; ++ix) {
        const cInt cx = (i0 + static_cast<cInt>(ix)) * tile + tile / 2;
        while (next < crossings.size() && crossings[next].first < cx) winding += crossings[next++].second;
        inside[iy * nx + ix] = winding != 0 ? 1 : 0;
      }
    }

    Paths pieces;
    for (std::size_t iy = 0; iy < ny; ++iy)
      for (std::size_t ix = 0; ix < nx; ++ix) {
        const std::size_t t = iy * nx + ix;
        if (edges[t].empty()) {
          // Deep inside: the whole tile, and as far beyond as a neighbour's result reaches.
          if (inside[t]) pieces.push_back(tile_box(ix, iy).grown(kInputSlack).ring());
          continue;
        }
        std::vector<cInt> key = key_head(1, delta, arc_tolerance);
        key.insert(key.end(), {std::bit_cast<cInt>(tile_epsilon), tile, i0 + static_cast<cInt>(ix),
                               j0 + static_cast<cInt>(iy), inside[t]});
        key.insert(key.end(), edges[t].begin(), edges[t].end());
        const std::uint64_t hash = cache ? hash_of(key) : 0;
        if (cache)
          if (const auto* e = cache->find(hash, key)) {
            ++counters->hits;
            pieces.insert(pieces.end(), e->tile.begin(), e->tile.end());
            continue;
          }
        Paths result = tile_result(rings, tile_box(ix, iy).grown(input_reach()));
        pieces.insert(pieces.end(), result.begin(), result.end());
        if (cache) {
          ++counters->misses;
          cache->add(hash, std::move(key)).tile = std::move(result);
        }
      }
    if (pieces.empty()) return;
    ClipperLib::Clipper join;
    join.AddPaths(pieces, ClipperLib::ptSubject, true);
    ClipperLib::PolyTree tree;
    join.Execute(ClipperLib::ctUnion, tree, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
    append_polygons(tree, out);
  }

  // The erosion of the polygon clipped to `input`.
  Paths tile_result(const Paths& rings, const IntBox& input) const {
    Paths clipped;
    for (const auto& r : rings) {  // the outer ring first, as erode() needs
      const IntBox b = box_of(r);
      if (input.holds(b)) {
        clipped.push_back(r);
      } else if (input.meets(b)) {
        Path c = clip_to_box(r, input);
        if (c.size() >= 3 && ClipperLib::Area(c) != 0.0) clipped.push_back(std::move(c));
      }
    }
    if (clipped.empty()) return {};
    Paths eroded;
    erode(clipped, static_cast<double>(delta), arc_tolerance, eroded);
    if (tile_epsilon > 0.0) simplify_tile(eroded, input.grown(-input_reach()));
    return eroded;
  }

  // RDP on a tile's result, but for its vertices within 2 kInputSlack +
  // the epsilon of the tile's sides: there the neighbours' results overlap
  // it (kInputSlack each way), and with the vertices of both kept there as
  // the offset made them, the union joins them as it joins the
  // unsimplified results. A chord from the band inwards moves the boundary
  // by at most the epsilon, as anywhere. Rings that would meet (RDP does
  // not see other rings, nor the rest of its own) keep the tile as it was.
  void simplify_tile(Paths& result, const IntBox& tile_box) const {
    const cInt band = 2 * kInputSlack + static_cast<cInt>(std::ceil(tile_epsilon));
    const IntBox inner = tile_box.grown(-band);
    auto fixed = [&](const IntPoint& p) { return !(inner.x0 < p.X && p.X < inner.x1 && inner.y0 < p.Y && p.Y < inner.y1); };
    Paths simplified;
    simplified.reserve(result.size());
    for (const Path& ring : result) {
      Path s = simplified_ring(ring, tile_epsilon, fixed);
      simplified.push_back(s.empty() ? ring : std::move(s));
    }
    if (!rings_meet(simplified)) result = std::move(simplified);
  }
};

}  // namespace

mapping::TypedOpResult offset_inward(const mapping::TypedMultiPolygon& free_space, const InwardOffset& how,
                                     OffsetTileCache* cache) {
  mapping::TypedOpResult result;
  if (!(how.distance_m > 0.0) || how.points_per_circle < 4 || !(how.tile_m >= 0.0) || how.tile_min_vertices < 0) {
    result.error = "bad offset (distance must be > 0, points_per_circle >= 4, tile_m >= 0)";
    return result;
  }
  // Round joins: Clipper puts their vertices on the arc and takes as many as
  // keep the chords within ArcTolerance of it. A chord cuts into the
  // clearance by that much (6 mm with 16 vertices per circle at 0.32 m, where
  // Boost's joins lost 1-2 mm on the maps of the tests), so the tolerance is
  // also at most kMaxArcErrorM; the C-space's simplification removes most
  // of the extra vertices again.
  constexpr double kMaxArcErrorM = 1e-3;
  Eroder eroder;
  eroder.delta = static_cast<cInt>(std::llround(how.distance_m * kUnitsPerM));
  eroder.arc_tolerance =
      std::min(how.distance_m * (1.0 - std::cos(std::numbers::pi / how.points_per_circle)), kMaxArcErrorM) * kUnitsPerM;
  eroder.largest_tile = static_cast<cInt>(std::llround(how.tile_m * kUnitsPerM));
  // A tile narrower than its input's growth would cost more than it saves.
  if (eroder.largest_tile > 0 && eroder.largest_tile < eroder.delta) eroder.largest_tile = eroder.delta;
  eroder.tile_min_vertices = how.tile_min_vertices;
  const double seam_epsilon_m = std::min(kSeamEpsilonM, how.simplify_epsilon_m / 2.0);
  if (how.simplify_epsilon_m > 0.0) eroder.tile_epsilon = (how.simplify_epsilon_m - seam_epsilon_m) * kUnitsPerM;
  if (cache) {
    eroder.cache = cache->impl_.get();
    eroder.counters = &cache->counters_;
    ++eroder.cache->call;
  }

  for (const auto& input : free_space)
    if (!on_grid(input.geometry)) {
      result.error = "a coordinate is not finite or beyond 1e9 m";
      return result;
    }
  // Polygon by polygon: the polygons of a map are interior-disjoint, and a
  // point of one is nearer its own boundary than any other polygon's (a
  // segment to another polygon's edge leaves its own first), so its C-space
  // depends on its own rings only. Clipper's sweep costs about its scanbeams
  // times the edges across each, so several small sweeps cost less than one
  // across the whole map.
  mapping::MultiPolygon geometry;
  std::vector<char> from_tiles;  // per polygon of geometry
  try {
    for (const auto& input : free_space) {
      Paths rings;
      rings.push_back(to_clipper(input.geometry.outer()));
      if (rings[0].size() < 3) continue;
      for (const auto& hole : input.geometry.inners()) {
        rings.push_back(to_clipper(hole));
        if (rings.back().size() < 3) rings.pop_back();
      }
      const bool tiled = eroder.polygon(rings, geometry);
      from_tiles.resize(geometry.size(), tiled ? 1 : 0);
    }
  } catch (const std::exception& e) {
    result.error = std::string("offset failed: ") + e.what();
    return result;
  }
  if (cache) eroder.cache->drop_old();
  if (!how.type_edges) {
    result.polygons = mapping::with_uniform_type(geometry, mapping::EdgeType::kObstacle);
  } else {
    // Each output edge takes the type of the map edge it was offset from.
    mapping::EdgeTypeIndex index;
    index.add(free_space);
    index.build();
    // The search reaches past distance_m by more than the grid's rounding.
    result.polygons =
        mapping::assign_types(geometry, index, how.distance_m + 1e-3, mapping::TypedOpOptions{}, &result.reassign);
  }
  if (how.simplify_epsilon_m > 0.0) {
    // A whole polygon by the epsilon; a tiled one's tiles are simplified
    // already but for the seams, where the union's vertices also are.
    mapping::TypedMultiPolygon simplified;
    simplified.reserve(result.polygons.size());
    for (std::size_t k = 0; k < result.polygons.size(); ++k) {
      const bool tiled = k < from_tiles.size() && from_tiles[k];
      for (auto& p : mapping::simplify_typed(std::span(&result.polygons[k], 1),
                                             tiled ? seam_epsilon_m : how.simplify_epsilon_m))
        simplified.push_back(std::move(p));
    }
    result.polygons = std::move(simplified);
  }
  result.ok = true;
  return result;
}


mapping::MultiPolygon dilated_polyline(const std::vector<mapping::Point>& points, double radius_m) {
  return dilated_polylines({points}, radius_m);
}

mapping::MultiPolygon dilated_polylines(const std::vector<std::vector<mapping::Point>>& polylines, double radius_m) {
  if (!(radius_m > 0.0) || radius_m > kMaxAbsCoordinateM) return {};
  for (const auto& points : polylines)
    if (!std::all_of(points.begin(), points.end(), [](const auto& p) { return on_grid(p); })) return {};
  ClipperLib::ClipperOffset offset;
  offset.ArcTolerance = std::min(radius_m, 1e-3) * kUnitsPerM;
  bool any = false;
  for (const auto& points : polylines) {
    if (points.empty()) continue;
    Path path;
    path.reserve(points.size());
    for (const auto& p : points) {
      const IntPoint q(static_cast<cInt>(std::llround(p.x() * kUnitsPerM)),
                       static_cast<cInt>(std::llround(p.y() * kUnitsPerM)));
      if (path.empty() || !(path.back() == q)) path.push_back(q);
    }
    // A single point is a closed path of one vertex to Clipper; an open path
    // with round ends gives its disk.
    offset.AddPath(path, ClipperLib::jtRound, ClipperLib::etOpenRound);
    any = true;
  }
  if (!any) return {};
  ClipperLib::PolyTree tree;
  offset.Execute(tree, radius_m * kUnitsPerM);
  mapping::MultiPolygon out;
  append_polygons(tree, out);
  return out;
}

namespace {

std::optional<mapping::MultiPolygon> clipped(ClipperLib::ClipType operation, const mapping::MultiPolygon& a,
                                             const mapping::MultiPolygon& b) {
  if (!on_grid(a) || !on_grid(b)) return std::nullopt;
  ClipperLib::Clipper clipper;
  add_rings(a, ClipperLib::ptSubject, clipper);
  add_rings(b, ClipperLib::ptClip, clipper);
  ClipperLib::PolyTree tree;
  // Non-zero winding: our outer rings and holes wind opposite ways, so the
  // inside of a hole counts zero, as outside any polygon.
  if (!clipper.Execute(operation, tree, ClipperLib::pftNonZero, ClipperLib::pftNonZero)) return std::nullopt;
  mapping::MultiPolygon out;
  append_polygons(tree, out);
  return out;
}

}  // namespace

std::optional<mapping::MultiPolygon> united(const mapping::MultiPolygon& a, const mapping::MultiPolygon& b) {
  return clipped(ClipperLib::ctUnion, a, b);
}

std::optional<mapping::MultiPolygon> subtracted(const mapping::MultiPolygon& a, const mapping::MultiPolygon& b) {
  return clipped(ClipperLib::ctDifference, a, b);
}

}  // namespace pex::planning
