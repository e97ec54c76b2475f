#include "make_world.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace pex::make_world {

namespace {

constexpr std::array<int, 4> kDx{1, 0, -1, 0};  // E, N, W, S: counter-clockwise
constexpr std::array<int, 4> kDy{0, 1, 0, -1};

struct Bitmap {
  int width = 0, height = 0;
  std::vector<std::uint8_t> on;
  bool at(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height && on[idx(x, y)]; }
  std::size_t idx(int x, int y) const { return static_cast<std::size_t>(y) * width + x; }
};

// Labels the components of the cells where `member` is true; returns the label
// per cell (-1 outside) and the component count. 4- or 8-connected.
template <class Member>
int label_components(int width, int height, bool eight, Member member, std::vector<int>& labels) {
  labels.assign(static_cast<std::size_t>(width) * height, -1);
  int count = 0;
  std::vector<int> stack;
  for (int start = 0; start < width * height; ++start) {
    if (labels[start] >= 0 || !member(start % width, start / width)) continue;
    labels[start] = count;
    stack.push_back(start);
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      const int cx = c % width, cy = c / width;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if ((dx == 0 && dy == 0) || (!eight && dx != 0 && dy != 0)) continue;
          const int nx = cx + dx, ny = cy + dy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const int n = ny * width + nx;
          if (labels[n] >= 0 || !member(nx, ny)) continue;
          labels[n] = count;
          stack.push_back(n);
        }
      }
    }
    ++count;
  }
  return count;
}

// The cells 4-connected to `seed` through cells where member(index) is true
// (the seed is in, whatever member says of it): 1 in, 0 out.
template <class Member>
std::vector<std::uint8_t> flood_fill(int width, int height, std::size_t seed, Member member) {
  std::vector<std::uint8_t> in(static_cast<std::size_t>(width) * height, 0);
  std::vector<std::size_t> stack{seed};
  in[seed] = 1;
  while (!stack.empty()) {
    const std::size_t c = stack.back();
    stack.pop_back();
    const int cx = static_cast<int>(c % width), cy = static_cast<int>(c / width);
    for (int d = 0; d < 4; ++d) {
      const int nx = cx + kDx[d], ny = cy + kDy[d];
      if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
      const std::size_t ni = static_cast<std::size_t>(ny) * width + nx;
      if (in[ni] || !member(ni)) continue;
      in[ni] = 1;
      stack.push_back(ni);
    }
  }
  return in;
}

// 1D squared Euclidean distance transform (Felzenszwalb & Huttenlocher 2012).
void edt_1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v, std::vector<double>& z) {
  const int n = static_cast<int>(f.size());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int k = 0;
  v[0] = 0;
  z[0] = -kInf;
  z[1] = kInf;
  for (int q = 1; q < n; ++q) {
    if (f[q] == kInf) continue;
    // Skip leading infinite parabolas.
    if (f[v[k]] == kInf) {
      v[k] = q;
      z[k] = -kInf;
      z[k + 1] = kInf;
      continue;
    }
    double s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    while (s <= z[k]) {
      --k;
      s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kInf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const double dq = q - v[k];
    d[q] = f[v[k]] == kInf ? kInf : dq * dq + f[v[k]];
  }
}

// Distance (in cells) from every cell centre to the nearest centre of a cell
// where `source` is set.
std::vector<double> distance_transform(const Bitmap& source) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const int w = source.width, h = source.height;
  std::vector<double> g(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = source.on[i] ? 0.0 : kInf;
  const int n = std::max(w, h);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (int x = 0; x < w; ++x) {  // columns
    f.resize(h);
    d.resize(h);
    for (int y = 0; y < h; ++y) f[y] = g[source.idx(x, y)];
    edt_1d(f, d, v, z);
    for (int y = 0; y < h; ++y) g[source.idx(x, y)] = d[y];
  }
  for (int y = 0; y < h; ++y) {  // rows
    f.resize(w);
    d.resize(w);
    for (int x = 0; x < w; ++x) f[x] = g[source.idx(x, y)];
    edt_1d(f, d, v, z);
    for (int x = 0; x < w; ++x) g[source.idx(x, y)] = std::sqrt(d[x]);
  }
  return g;
}

// The boundaries of the set cells of `region`, as rings through the midpoints
// of the cell edges between a set and an unset cell, the set cells on the
// left. Where two set cells touch only at a corner the ring turns left, so
// they stay apart (the region is 4-connected, its complement 8-connected).
std::vector<Ring> trace_boundaries(const Bitmap& region, double origin_x, double origin_y, double cell) {
  const int vw = region.width + 1, vh = region.height + 1;
  std::vector<std::uint8_t> out(static_cast<std::size_t>(vw) * vh, 0);  // outgoing edge directions per vertex
  auto vid = [vw](int x, int y) { return static_cast<std::size_t>(y) * vw + x; };
  for (int y = 0; y < region.height; ++y) {
    for (int x = 0; x < region.width; ++x) {
      if (!region.at(x, y)) continue;
      if (!region.at(x, y - 1)) out[vid(x, y)] |= 1u << 0;          // bottom edge, going E
      if (!region.at(x + 1, y)) out[vid(x + 1, y)] |= 1u << 1;      // right edge, going N
      if (!region.at(x, y + 1)) out[vid(x + 1, y + 1)] |= 1u << 2;  // top edge, going W
      if (!region.at(x - 1, y)) out[vid(x, y + 1)] |= 1u << 3;      // left edge, going S
    }
  }
  std::vector<Ring> rings;
  for (int sy = 0; sy < vh; ++sy) {
    for (int sx = 0; sx < vw; ++sx) {
      while (out[vid(sx, sy)] != 0) {
        const int start_dir = std::countr_zero(out[vid(sx, sy)]);
        Ring ring;
        int x = sx, y = sy, dir = start_dir;
        while (true) {
          out[vid(x, y)] &= static_cast<std::uint8_t>(~(1u << dir));
          ring.push_back({origin_x + (x + 0.5 * kDx[dir]) * cell, origin_y + (y + 0.5 * kDy[dir]) * cell});
          x += kDx[dir];
          y += kDy[dir];
          std::uint8_t avail = out[vid(x, y)];
          const bool at_start = x == sx && y == sy;
          if (at_start) avail |= static_cast<std::uint8_t>(1u << start_dir);
          int next = -1;
          for (int turn : {1, 0, 3}) {  // left, straight, right
            const int d = (dir + turn) % 4;
            if (avail & (1u << d)) {
              next = d;
              break;
            }
          }
          if (next < 0 || (at_start && next == start_dir)) break;
          dir = next;
        }
        rings.push_back(std::move(ring));
      }
    }
  }
  return rings;
}

double point_segment_distance(const Point& p, const Point& a, const Point& b) {
  const double vx = b.x - a.x, vy = b.y - a.y;
  const double len2 = vx * vx + vy * vy;
  double t = len2 > 0 ? ((p.x - a.x) * vx + (p.y - a.y) * vy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - (a.x + t * vx), p.y - (a.y + t * vy));
}

void draw_line(Picture& pic, double x0, double y0, double x1, double y1, std::array<std::uint8_t, 3> color) {
  const int steps = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
  for (int i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    const int px = static_cast<int>(std::floor(x0 + t * (x1 - x0)));
    const int py = static_cast<int>(std::floor(y0 + t * (y1 - y0)));
    if (px < 0 || py < 0 || px >= pic.width || py >= pic.height) continue;
    std::copy(color.begin(), color.end(), pic.rgb.begin() + 3 * (static_cast<std::size_t>(py) * pic.width + px));
  }
}

}  // namespace

std::string GridOptions::validate() const {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) return "cell_m must be > 0";
  if (!(max_range_m > min_range_m) || !(min_range_m >= 0.0)) return "need 0 <= min_range_m < max_range_m";
  if (!(hit_log_odds > 0.0)) return "hit_log_odds must be > 0";
  if (!(miss_log_odds < 0.0)) return "miss_log_odds must be < 0";
  if (!(margin_m >= 0.0)) return "margin_m must be >= 0";
  return "";
}

OccupancyGrid::OccupancyGrid(double origin_x_m, double origin_y_m, int width, int height, double cell_m)
    : origin_x_m_(origin_x_m),
      origin_y_m_(origin_y_m),
      width_(width),
      height_(height),
      cell_m_(cell_m),
      cells_(static_cast<std::size_t>(width) * height, 0.0f) {}

int OccupancyGrid::cell_x(double x_m) const { return static_cast<int>(std::floor((x_m - origin_x_m_) / cell_m_)); }
int OccupancyGrid::cell_y(double y_m) const { return static_cast<int>(std::floor((y_m - origin_y_m_) / cell_m_)); }

void OccupancyGrid::integrate(const PosedScan& scan, const GridOptions& options) {
  const double sx = (scan.sensor.x_m - origin_x_m_) / cell_m_;  // in cells
  const double sy = (scan.sensor.y_m - origin_y_m_) / cell_m_;
  const int start_x = static_cast<int>(std::floor(sx)), start_y = static_cast<int>(std::floor(sy));
  if (!contains(start_x, start_y)) return;
  const auto hit = static_cast<float>(options.hit_log_odds);
  const auto miss = static_cast<float>(options.miss_log_odds);
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < options.min_range_m) continue;
    const bool no_return = r >= scan.no_return_m;
    if (no_return && !options.free_on_no_return) continue;
    const bool is_hit = !no_return && r <= options.max_range_m;
    const double length = is_hit ? r : options.max_range_m;
    const double angle = scan.sensor.theta_rad + scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double dx = std::cos(angle), dy = std::sin(angle);
    const double ex = sx + dx * length / cell_m_, ey = sy + dy * length / cell_m_;
    const int end_x = static_cast<int>(std::floor(ex)), end_y = static_cast<int>(std::floor(ey));
    // Amanatides–Woo: step from cell to cell along the beam.
    int x = start_x, y = start_y;
    const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const double t_delta_x = dx != 0 ? std::abs(1.0 / dx) : kInf;
    const double t_delta_y = dy != 0 ? std::abs(1.0 / dy) : kInf;
    double t_max_x = dx != 0 ? (dx > 0 ? (std::floor(sx) + 1 - sx) : (sx - std::floor(sx))) * t_delta_x : kInf;
    double t_max_y = dy != 0 ? (dy > 0 ? (std::floor(sy) + 1 - sy) : (sy - std::floor(sy))) * t_delta_y : kInf;
    const double t_end = length / cell_m_;
    bool inside = true;
    while (!(x == end_x && y == end_y)) {
      add(x, y, miss);
      if (t_max_x < t_max_y) {
        if (t_max_x > t_end) break;
        x += step_x;
        t_max_x += t_delta_x;
      } else {
        if (t_max_y > t_end) break;
        y += step_y;
        t_max_y += t_delta_y;
      }
      if (!contains(x, y)) {
        inside = false;
        break;
      }
    }
    if (!inside) continue;
    if (x == end_x && y == end_y) add(x, y, is_hit ? hit : miss);
  }
}

OccupancyGrid build_grid(const std::vector<PosedScan>& scans, const GridOptions& options) {
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  for (const auto& scan : scans) {
    for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
      const double r = scan.ranges_m[i];
      if (!std::isfinite(r) || r < options.min_range_m) continue;
      if (r >= scan.no_return_m && !options.free_on_no_return) continue;
      const double length = std::min(r, options.max_range_m);
      const double angle = scan.sensor.theta_rad + scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
      const double x = scan.sensor.x_m + length * std::cos(angle), y = scan.sensor.y_m + length * std::sin(angle);
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
    }
    min_x = std::min(min_x, scan.sensor.x_m);
    max_x = std::max(max_x, scan.sensor.x_m);
    min_y = std::min(min_y, scan.sensor.y_m);
    max_y = std::max(max_y, scan.sensor.y_m);
  }
  if (!std::isfinite(min_x)) return OccupancyGrid(0, 0, 1, 1, options.cell_m);
  const double cell = options.cell_m;
  const double ox = std::floor((min_x - options.margin_m) / cell) * cell;
  const double oy = std::floor((min_y - options.margin_m) / cell) * cell;
  const int w = static_cast<int>(std::ceil((max_x + options.margin_m - ox) / cell)) + 1;
  const int h = static_cast<int>(std::ceil((max_y + options.margin_m - oy) / cell)) + 1;
  OccupancyGrid grid(ox, oy, w, h, cell);
  for (const auto& scan : scans) grid.integrate(scan, options);
  return grid;
}

double signed_area(const Ring& ring) {
  double a = 0.0;
  for (std::size_t i = 0, n = ring.size(); i < n; ++i) {
    const Point& p = ring[i];
    const Point& q = ring[(i + 1) % n];
    a += p.x * q.y - q.x * p.y;
  }
  return 0.5 * a;
}

Ring simplify_ring(const Ring& ring, double tolerance_m) {
  const std::size_t n = ring.size();
  if (n < 4) return ring;
  // Split at point 0 and the point farthest from it; simplify both chains.
  std::size_t far = 0;
  double far_d = -1.0;
  for (std::size_t i = 1; i < n; ++i) {
    const double d = std::hypot(ring[i].x - ring[0].x, ring[i].y - ring[0].y);
    if (d > far_d) {
      far_d = d;
      far = i;
    }
  }
  std::vector<bool> keep(n, false);
  keep[0] = keep[far] = true;
  auto at = [&](std::size_t i) -> const Point& { return ring[i % n]; };
  std::vector<std::pair<std::size_t, std::size_t>> stack{{0, far}, {far, n}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (b <= a + 1) continue;
    std::size_t worst = a;
    double worst_d = -1.0;
    for (std::size_t i = a + 1; i < b; ++i) {
      const double d = point_segment_distance(at(i), at(a), at(b));
      if (d > worst_d) {
        worst_d = d;
        worst = i;
      }
    }
    if (worst_d > tolerance_m) {
      keep[worst] = true;
      stack.push_back({a, worst});
      stack.push_back({worst, b});
    }
  }
  Ring out;
  for (std::size_t i = 0; i < n; ++i)
    if (keep[i]) out.push_back(ring[i]);
  if (out.size() < 3) return ring;  // a ring flattened to a segment: keep it as it was
  return out;
}

std::size_t World::edges() const {
  std::size_t e = boundary.size();
  for (const auto& r : obstacles) e += r.size();
  return e;
}

std::variant<World, std::string> extract_world(const OccupancyGrid& grid, const std::vector<Pose2>& trajectory,
                                               const WorldOptions& options) {
  const int w = grid.width(), h = grid.height();
  const double cell = grid.cell_m();
  const std::size_t n = static_cast<std::size_t>(w) * h;
  World world;
  auto idx = [w](int x, int y) { return static_cast<std::size_t>(y) * w + x; };

  // 1. Classes by thresholds; the grid's border ring is never free, so every
  //    boundary closes inside the grid.
  auto& cls = world.classes;
  cls.assign(n, CellClass::kUnknown);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float l = grid.log_odds(x, y);
      if (l > options.occupied_log_odds) cls[idx(x, y)] = CellClass::kOccupied;
      else if (l < options.free_log_odds && x > 0 && y > 0 && x < w - 1 && y < h - 1)
        cls[idx(x, y)] = CellClass::kFree;
    }
  }

  // 2. Specks: small occupied components become unknown.
  std::vector<int> labels;
  const int occ_count = label_components(
      w, h, true, [&](int x, int y) { return cls[idx(x, y)] == CellClass::kOccupied; }, labels);
  {
    std::vector<int> size(occ_count, 0);
    for (std::size_t i = 0; i < n; ++i)
      if (labels[i] >= 0) ++size[labels[i]];
    for (std::size_t i = 0; i < n; ++i) {
      if (labels[i] >= 0 && size[labels[i]] < options.min_obstacle_cells) cls[i] = CellClass::kUnknown;
    }
    for (int c = 0; c < occ_count; ++c)
      if (size[c] < options.min_obstacle_cells) ++world.specks_dropped;
  }

  // 3. Spikes: free cells outside the opening of the free set (no all-free
  //    (2k+1)² block holds them) that touch unknown space become unknown.
  if (options.spike_width_cells > 0) {
    const int k = options.spike_width_cells;
    auto is_free = [&](int x, int y) {
      return x >= 0 && y >= 0 && x < w && y < h && cls[idx(x, y)] == CellClass::kFree;
    };
    // Summed-area table of free cells for O(1) block tests.
    std::vector<int> sat(static_cast<std::size_t>(w + 1) * (h + 1), 0);
    auto s = [&](int x, int y) -> int& { return sat[static_cast<std::size_t>(y) * (w + 1) + x]; };
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) s(x + 1, y + 1) = s(x, y + 1) + s(x + 1, y) - s(x, y) + (is_free(x, y) ? 1 : 0);
    auto block_free = [&](int cx, int cy) {  // the block centred on (cx, cy) is all free
      const int x0 = cx - k, y0 = cy - k, x1 = cx + k + 1, y1 = cy + k + 1;
      if (x0 < 0 || y0 < 0 || x1 > w || y1 > h) return false;
      return s(x1, y1) - s(x0, y1) - s(x1, y0) + s(x0, y0) == (2 * k + 1) * (2 * k + 1);
    };
    std::vector<std::uint8_t> cut(n, 0);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (!is_free(x, y)) continue;
        bool in_opening = false;
        for (int cy = y - k; cy <= y + k && !in_opening; ++cy)
          for (int cx = x - k; cx <= x + k && !in_opening; ++cx) in_opening = block_free(cx, cy);
        if (in_opening) continue;
        bool touches_unknown = false;
        for (int dy = -1; dy <= 1 && !touches_unknown; ++dy)
          for (int dx = -1; dx <= 1 && !touches_unknown; ++dx) {
            const int nx = x + dx, ny = y + dy;
            touches_unknown = nx >= 0 && ny >= 0 && nx < w && ny < h && cls[idx(nx, ny)] == CellClass::kUnknown;
          }
        if (touches_unknown) cut[idx(x, y)] = 1;
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (cut[i]) {
        cls[i] = CellClass::kUnknown;
        ++world.spike_cells_cut;
      }
    }
  }

  // 4. The free region: the 4-connected free cells joined to the first
  //    trajectory pose that stands in a free cell.
  std::size_t seed = n;
  for (const auto& p : trajectory) {
    const int x = grid.cell_x(p.x_m), y = grid.cell_y(p.y_m);
    if (grid.contains(x, y) && cls[idx(x, y)] == CellClass::kFree) {
      seed = idx(x, y);
      break;
    }
  }
  if (seed == n) return std::string("no trajectory pose stands in a free cell");
  auto& region = world.region;
  region = flood_fill(w, h, seed, [&](std::size_t i) { return cls[i] == CellClass::kFree; });

  // 5. Pockets: 8-connected components of the rest. The one touching the
  //    grid's border is outside; the others are holes in the region. Holes
  //    without an occupied cell (gaps between rays) and tiny clutter are filled.
  {
    const int count = label_components(w, h, true, [&](int x, int y) { return !region[idx(x, y)]; }, labels);
    std::vector<std::size_t> cells(count, 0), occupied(count, 0);
    std::vector<bool> outside(count, false);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int l = labels[idx(x, y)];
        if (l < 0) continue;
        ++cells[l];
        if (cls[idx(x, y)] == CellClass::kOccupied) ++occupied[l];
        if (x == 0 || y == 0 || x == w - 1 || y == h - 1) outside[l] = true;
      }
    }
    const double cell_area = cell * cell;
    std::vector<bool> fill(count, false);
    for (int l = 0; l < count; ++l) {
      if (outside[l]) continue;
      const double area = static_cast<double>(cells[l]) * cell_area;
      if (occupied[l] == 0 && area <= options.max_unseen_pocket_m2) {
        fill[l] = true;
        ++world.pockets_filled;
      } else if (occupied[l] > 0 && area < options.min_clutter_m2) {
        fill[l] = true;
        ++world.clutter_dropped;
      }
    }
    for (std::size_t i = 0; i < n; ++i)
      if (labels[i] >= 0 && fill[labels[i]]) region[i] = 1;
  }

  // 6. Walls: the region's boundaries, simplified.
  {
    Bitmap bm{w, h, region};
    auto rings = trace_boundaries(bm, grid.origin_x_m(), grid.origin_y_m(), cell);
    bool have_outer = false;
    for (auto& ring : rings) {
      Ring simple = simplify_ring(ring, options.simplify_m);
      const double area = signed_area(ring);
      if (area > 0 && !have_outer) {
        world.boundary = std::move(simple);
        have_outer = true;
      } else if (area > 0) {
        return std::string("the free region has two outer boundaries (internal error)");
      } else {
        std::reverse(simple.begin(), simple.end());
        world.obstacles.push_back(std::move(simple));
      }
    }
    if (!have_outer) return std::string("the free region has no boundary");
  }

  // 7. Clearance of every cell centre from the walls (the wall runs half a
  //    cell from the centres of the cells beside it).
  std::vector<double> clearance;
  {
    Bitmap blocked{w, h, std::vector<std::uint8_t>(n)};
    for (std::size_t i = 0; i < n; ++i) blocked.on[i] = region[i] ? 0 : 1;
    clearance = distance_transform(blocked);
    for (auto& c : clearance) c = c * cell - 0.5 * cell;
  }

  // 8. START: the first trajectory pose clear of every wall.
  std::size_t start_cell = n;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const int x = grid.cell_x(trajectory[i].x_m), y = grid.cell_y(trajectory[i].y_m);
    if (!grid.contains(x, y) || !region[idx(x, y)] || clearance[idx(x, y)] < options.start_clearance_m) continue;
    world.start = trajectory[i];
    world.start_index = i;
    start_cell = idx(x, y);
    break;
  }
  if (start_cell == n) return std::string("no trajectory pose is clear of the walls by start_clearance_m");

  // 9. Where the disk's centre goes from START.
  auto& reach = world.reachable;
  reach = flood_fill(w, h, start_cell,
                     [&](std::size_t i) { return region[i] && clearance[i] > options.robot_radius_m; });

  // 10. Figures.
  std::size_t region_cells = 0, reach_cells = 0;
  for (std::size_t i = 0; i < n; ++i) {
    region_cells += region[i];
    reach_cells += reach[i];
    if (cls[i] == CellClass::kOccupied) ++world.occupied_cells;
    else if (cls[i] == CellClass::kFree) ++world.free_cells;
    else ++world.unknown_cells;
  }
  world.free_area_m2 = static_cast<double>(region_cells) * cell * cell;
  world.reachable_area_m2 = static_cast<double>(reach_cells) * cell * cell;
  for (const auto& p : trajectory) {
    const int x = grid.cell_x(p.x_m), y = grid.cell_y(p.y_m);
    if (grid.contains(x, y) && region[idx(x, y)]) ++world.trajectory_in_region;
    if (grid.contains(x, y) && reach[idx(x, y)]) ++world.trajectory_reachable;
  }
  world.min_x = world.min_y = std::numeric_limits<double>::infinity();
  world.max_x = world.max_y = -std::numeric_limits<double>::infinity();
  auto grow = [&](const Ring& r) {
    for (const auto& p : r) {
      world.min_x = std::min(world.min_x, p.x);
      world.min_y = std::min(world.min_y, p.y);
      world.max_x = std::max(world.max_x, p.x);
      world.max_y = std::max(world.max_y, p.y);
    }
  };
  grow(world.boundary);
  for (const auto& r : world.obstacles) grow(r);
  return world;
}

void translate(World& world, double dx_m, double dy_m) {
  auto move = [&](Ring& r) {
    for (auto& p : r) {
      p.x += dx_m;
      p.y += dy_m;
    }
  };
  move(world.boundary);
  for (auto& r : world.obstacles) move(r);
  world.start.x_m += dx_m;
  world.start.y_m += dy_m;
  world.min_x += dx_m;
  world.max_x += dx_m;
  world.min_y += dy_m;
  world.max_y += dy_m;
}

namespace {

void append_points(std::ostringstream& out, const Ring& ring) {
  char buf[64];
  for (std::size_t i = 0; i <= ring.size(); ++i) {
    const Point& p = ring[i % ring.size()];
    std::snprintf(buf, sizeof buf, "%.3f %.3f", p.x, p.y);
    if (i > 0) out << (i % 8 == 0 ? ",\n  " : ", ");
    out << buf;
  }
}

}  // namespace

std::string to_wkt(const World& world, const std::vector<std::string>& header) {
  std::ostringstream out;
  for (const auto& line : header) out << "# " << line << '\n';
  char buf[128];
  std::snprintf(buf, sizeof buf, "START %.3f %.3f %.4f\n", world.start.x_m, world.start.y_m, world.start.theta_rad);
  out << '\n' << buf;
  out << "# outer boundary of the free space (" << world.boundary.size() << " edges)\nLINESTRING(";
  append_points(out, world.boundary);
  out << ")\n";
  out << "# clutter, pillars and wall blocks inside it (" << world.obstacles.size() << " polygons)\n";
  for (const auto& r : world.obstacles) {
    out << "POLYGON((";
    append_points(out, r);
    out << "))\n";
  }
  return out.str();
}

std::string to_svg(const World& world) {
  std::ostringstream out;
  const double m = 1.0;
  const double x0 = world.min_x - m, y0 = world.min_y - m;
  const double wd = world.max_x - world.min_x + 2 * m, ht = world.max_y - world.min_y + 2 * m;
  char buf[160];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"%.3f %.3f %.3f %.3f\">\n",
                wd * 25, ht * 25, x0, -(y0 + ht), wd, ht);
  out << buf << "<g transform=\"scale(1,-1)\">\n";
  auto path = [&](const Ring& r, const char* fill) {
    out << "<path fill=\"" << fill << "\" stroke=\"black\" stroke-width=\"0.04\" d=\"";
    for (std::size_t i = 0; i < r.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%s%.3f %.3f ", i == 0 ? "M" : "L", r[i].x, r[i].y);
      out << buf;
    }
    out << "Z\"/>\n";
  };
  path(world.boundary, "#f4f4f4");
  for (const auto& r : world.obstacles) path(r, "#888888");
  std::snprintf(buf, sizeof buf, "<circle cx=\"%.3f\" cy=\"%.3f\" r=\"0.25\" fill=\"red\"/>\n", world.start.x_m,
                world.start.y_m);
  out << buf << "</g>\n</svg>\n";
  return out.str();
}

Picture render(const World& world, const OccupancyGrid& grid, double dx_m, double dy_m,
               const std::vector<Pose2>& trajectory) {
  Picture pic;
  pic.width = grid.width();
  pic.height = grid.height();
  pic.rgb.assign(static_cast<std::size_t>(pic.width) * pic.height * 3, 0);
  const bool have_cells = world.classes.size() == static_cast<std::size_t>(pic.width) * pic.height;
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * grid.width() + x;
      std::array<std::uint8_t, 3> c{150, 150, 150};
      if (have_cells) {
        if (world.classes[i] == CellClass::kOccupied) c = {0, 0, 0};
        else if (world.classes[i] == CellClass::kFree) c = {255, 255, 255};
        if (world.region[i]) c = {200, 220, 255};
        if (world.reachable[i]) c = {200, 245, 200};
      }
      const int py = grid.height() - 1 - y;
      std::copy(c.begin(), c.end(), pic.rgb.begin() + 3 * (static_cast<std::size_t>(py) * pic.width + x));
    }
  }
  auto px = [&](double xm) { return (xm - dx_m - grid.origin_x_m()) / grid.cell_m(); };
  auto py = [&](double ym) { return grid.height() - (ym - dy_m - grid.origin_y_m()) / grid.cell_m(); };
  auto ring = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) {
      const Point& a = r[i];
      const Point& b = r[(i + 1) % r.size()];
      draw_line(pic, px(a.x), py(a.y), px(b.x), py(b.y), {220, 0, 0});
    }
  };
  ring(world.boundary);
  for (const auto& r : world.obstacles) ring(r);
  for (const auto& p : trajectory) {
    const int x = grid.cell_x(p.x_m), y = grid.cell_y(p.y_m);
    if (!grid.contains(x, y)) continue;
    const bool reached = have_cells && world.reachable[static_cast<std::size_t>(y) * grid.width() + x];
    const std::array<std::uint8_t, 3> c = reached ? std::array<std::uint8_t, 3>{0, 0, 160}
                                                  : std::array<std::uint8_t, 3>{255, 0, 255};
    std::copy(c.begin(), c.end(), pic.rgb.begin() + 3 * (static_cast<std::size_t>(grid.height() - 1 - y) * pic.width + x));
  }
  const double sx = px(world.start.x_m), sy = py(world.start.y_m);
  draw_line(pic, sx - 6, sy, sx + 6, sy, {255, 0, 0});
  draw_line(pic, sx, sy - 6, sx, sy + 6, {255, 0, 0});
  draw_line(pic, sx, sy, sx + 10 * std::cos(world.start.theta_rad), sy - 10 * std::sin(world.start.theta_rad),
            {0, 0, 255});
  return pic;
}

}  // namespace pex::make_world
