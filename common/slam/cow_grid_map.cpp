#include "slam/cow_grid_map.hpp"

#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>

#include "archive/byte_archive.hpp"

namespace pex::slam {
namespace {

// floor() for the cell index; std::floor is a library call on baseline x86-64.
inline int floor_to_int(float v) {
  const int i = static_cast<int>(v);
  return i - (v < static_cast<float>(i));
}

}  // namespace

int CowGridMapOptions::max_tiles_per_axis() const {
  const double tiles = std::ceil(max_extent_m / (resolution_m * CowGridMap::kTileSize));
  // A NaN or absurd option still gives a table an int can index.
  if (!(tiles >= 1.0)) return 1;
  return tiles < 1e6 ? static_cast<int>(tiles) : 1'000'000;
}

CowGridMap::CowGridMap(const CowGridMapOptions& options)
    : options_(options),
      inverse_resolution_(1.0 / options.resolution_m),
      max_tiles_per_axis_(options.max_tiles_per_axis()) {}

std::unique_ptr<ParticleMap> CowGridMap::clone() const { return std::make_unique<CowGridMap>(*this); }

std::size_t CowGridMap::tile_count() const {
  std::size_t n = 0;
  for (const auto& tile : tiles_) n += tile != nullptr;
  return n;
}

std::vector<const CowGridMap::Tile*> CowGridMap::tiles() const {
  std::vector<const Tile*> held;
  for (const auto& tile : tiles_)
    if (tile) held.push_back(tile.get());
  return held;
}

std::size_t CowGridMap::referenced_bytes() const {
  return tile_count() * sizeof(Tile) + tiles_.size() * sizeof(tiles_[0]);
}

const CowGridMap::Cell* CowGridMap::cell_at(double x_m, double y_m) const {
  return cell(static_cast<int>(std::floor(x_m * inverse_resolution_)),
              static_cast<int>(std::floor(y_m * inverse_resolution_)));
}

bool CowGridMap::grow_to_include(int tx, int ty) {
  const bool empty = tiles_w_ == 0;
  if (!empty && tx >= tile_x0_ && tx < tile_x0_ + tiles_w_ && ty >= tile_y0_ && ty < tile_y0_ + tiles_h_)
    return true;
  // The table that holds what it holds and (tx, ty); 64-bit, so far tiles cannot overflow.
  const std::int64_t need_x0 = empty ? tx : std::min(tile_x0_, tx);
  const std::int64_t need_y0 = empty ? ty : std::min(tile_y0_, ty);
  const std::int64_t need_x1 = empty ? std::int64_t{tx} + 1 : std::max<std::int64_t>(tile_x0_ + tiles_w_, tx + 1);
  const std::int64_t need_y1 = empty ? std::int64_t{ty} + 1 : std::max<std::int64_t>(tile_y0_ + tiles_h_, ty + 1);
  if (need_x1 - need_x0 > max_tiles_per_axis_ || need_y1 - need_y0 > max_tiles_per_axis_) return false;
  // Grow with a margin on the sides that grow, so a robot driving off the edge
  // does not reallocate per scan, as far as the extent allows.
  constexpr std::int64_t kMargin = 8;
  auto with_margin = [this, empty](std::int64_t lo, std::int64_t hi, int old_lo, int old_hi, int& out_lo,
                                   int& out_hi) {
    std::int64_t margin_lo = empty || lo < old_lo ? kMargin : 0;
    std::int64_t margin_hi = empty || hi > old_hi ? kMargin : 0;
    // Give back margin where the extent needs it (lo..hi itself fits).
    std::int64_t excess = (hi - lo) + margin_lo + margin_hi - max_tiles_per_axis_;
    if (excess > 0) {
      const std::int64_t from_lo = std::min(margin_lo, excess);
      margin_lo -= from_lo;
      margin_hi -= excess - from_lo;
    }
    out_lo = static_cast<int>(lo - margin_lo);
    out_hi = static_cast<int>(hi + margin_hi);
  };
  int x0, x1, y0, y1;
  with_margin(need_x0, need_x1, tile_x0_, tile_x0_ + tiles_w_, x0, x1);
  with_margin(need_y0, need_y1, tile_y0_, tile_y0_ + tiles_h_, y0, y1);
  std::vector<std::shared_ptr<Tile>> grown(static_cast<std::size_t>(x1 - x0) * static_cast<std::size_t>(y1 - y0));
  for (int y = 0; y < tiles_h_; ++y)
    for (int x = 0; x < tiles_w_; ++x)
      grown[static_cast<std::size_t>(y + tile_y0_ - y0) * (x1 - x0) + (x + tile_x0_ - x0)] =
          std::move(tiles_[static_cast<std::size_t>(y) * tiles_w_ + x]);
  tiles_ = std::move(grown);
  tile_x0_ = x0;
  tile_y0_ = y0;
  tiles_w_ = x1 - x0;
  tiles_h_ = y1 - y0;
  return true;
}

CowGridMap::Tile* CowGridMap::mutable_tile(int ix, int iy, int& index) {
  const int tx = ix >> kTileBits;
  const int ty = iy >> kTileBits;
  if (!grow_to_include(tx, ty)) return nullptr;
  auto& slot = tiles_[static_cast<std::size_t>(ty - tile_y0_) * tiles_w_ + (tx - tile_x0_)];
  if (!slot)
    slot = std::make_shared<Tile>();
  else if (slot.use_count() > 1)
    slot = std::make_shared<Tile>(*slot);  // copy on write
  index = ((iy & (kTileSize - 1)) << kTileBits) | (ix & (kTileSize - 1));
  slot->occupied |= std::uint64_t{1} << index;  // the caller adds a hit
  return slot.get();
}

void CowGridMap::update_normal(Cell& cell, const Scatter& scatter) const {
  cell.normal_x = 0;
  cell.normal_y = 0;
  if (cell.hits < 3) return;
  // Eigen decomposition of the 2x2 scatter [sxx sxy; sxy syy].
  const double a = scatter.sxx, b = scatter.sxy, c = scatter.syy;
  const double half_trace = 0.5 * (a + c);
  const double root = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  const double large = half_trace + root;
  const double small = half_trace - root;
  if (!(large > 1e-8) || small > options_.line_flatness * large) return;
  // The normal is the eigenvector of the smaller eigenvalue.
  double nx = b, ny = small - a;
  if (std::abs(nx) + std::abs(ny) < 1e-12) {
    nx = small - c;
    ny = b;
  }
  const double norm = std::hypot(nx, ny);
  if (!(norm > 0.0)) return;
  cell.normal_x = static_cast<std::int8_t>(std::lround(127.0 * nx / norm));
  cell.normal_y = static_cast<std::int8_t>(std::lround(127.0 * ny / norm));
}

std::size_t CowGridMap::insert(const Pose2& pose, const ScanPoints& scan) {
  std::size_t left_out = 0;
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  for (const BeamPoint& beam : scan.beams) {
    const double x = pose.x_m + c * beam.hit_x_m - s * beam.hit_y_m;
    const double y = pose.y_m + s * beam.hit_x_m + c * beam.hit_y_m;
    const double fx = x * inverse_resolution_;
    const double fy = y * inverse_resolution_;
    int index = 0;
    // The first test keeps the float -> int conversion defined.
    Tile* const held = std::abs(fx) < 1e8 && std::abs(fy) < 1e8
                           ? mutable_tile(static_cast<int>(std::floor(fx)), static_cast<int>(std::floor(fy)), index)
                           : nullptr;
    if (!held) {
      ++left_out;
      continue;
    }
    Tile& tile = *held;
    Cell& cell = tile.cells[static_cast<std::size_t>(index)];
    Scatter& scatter = tile.scatter[static_cast<std::size_t>(index)];
    if (cell.hits < std::numeric_limits<std::uint16_t>::max()) ++cell.hits;
    const float inv = 1.0f / static_cast<float>(cell.hits);
    // Welford's update of the mean and the scatter.
    const float dx = static_cast<float>(x) - cell.mean_x_m;
    const float dy = static_cast<float>(y) - cell.mean_y_m;
    cell.mean_x_m += dx * inv;
    cell.mean_y_m += dy * inv;
    const float dx2 = static_cast<float>(x) - cell.mean_x_m;
    const float dy2 = static_cast<float>(y) - cell.mean_y_m;
    scatter.sxx += dx * dx2;
    scatter.sxy += dx * dy2;
    scatter.syy += dy * dy2;
    update_normal(cell, scatter);
  }
  return left_out;
}

PoseEvaluation CowGridMap::evaluate(const Pose2& pose, const ScanPoints& scan) const {
  if (options_.kernel_radius_cells == 1 && !options_.check_free_before_hit) return evaluate_window3<true>(pose, scan);
  return evaluate_terms<true>(pose, scan);
}

double CowGridMap::log_likelihood(const Pose2& pose, const ScanPoints& scan) const {
  if (options_.kernel_radius_cells == 1 && !options_.check_free_before_hit)
    return evaluate_window3<false>(pose, scan).log_likelihood;
  return evaluate_terms<false>(pose, scan).log_likelihood;
}

namespace {
// The sums over a scan's beams that both evaluations keep: each beam adds
// its nearest hit's squared distance (or the penalty of no hit). Every
// expression in a fixed order, so that both give the same doubles.
template <bool kWithScore>
struct BeamSums {
  float inv_score_sigma;
  double inv_likelihood_sigma;
  double no_hit;
  double score = 0.0;
  double log_likelihood = 0.0;
  std::size_t matched_beams = 0;

  explicit BeamSums(const CowGridMapOptions& options)
      : inv_score_sigma(static_cast<float>(1.0 / options.score_sigma_m2)),
        inv_likelihood_sigma(1.0 / options.likelihood_sigma_m2),
        no_hit(options.null_log_likelihood * inv_likelihood_sigma) {}
  void miss() { log_likelihood += no_hit; }
  // best_d2: float max when no hit was near.
  void add(float best_d2) {
    if (best_d2 < std::numeric_limits<float>::max()) {
      if constexpr (kWithScore) score += std::exp(-best_d2 * inv_score_sigma);
      log_likelihood += -static_cast<double>(best_d2) * inv_likelihood_sigma;
      ++matched_beams;
    } else {
      miss();
    }
  }
  PoseEvaluation result() const {
    PoseEvaluation r;
    r.score = score;
    r.log_likelihood = log_likelihood;
    r.matched_beams = matched_beams;
    return r;
  }
};
}  // namespace

template <bool kWithScore>
PoseEvaluation CowGridMap::evaluate_window3(const Pose2& pose, const ScanPoints& scan) const {
  // Every expression as in evaluate_terms, in the same order: the same floats.
  const float c = static_cast<float>(std::cos(pose.theta_rad));
  const float s = static_cast<float>(std::sin(pose.theta_rad));
  const float px = static_cast<float>(pose.x_m);
  const float py = static_cast<float>(pose.y_m);
  const float inv_res = static_cast<float>(inverse_resolution_);
  const float along_weight = static_cast<float>(options_.along_line_weight);
  const std::size_t step = static_cast<std::size_t>(std::max(1, options_.beam_step));
  constexpr int kMask = kTileSize - 1;
  // The 3x3 window's bits in a tile's mask, shifted down to its corner.
  constexpr std::uint64_t kWindow = 0x7 | (0x7 << kTileSize) | (0x7ULL << (2 * kTileSize));
  BeamSums<kWithScore> sums(options_);
  // The end points and their cells are computed a chunk of beams at a time in
  // a loop the compiler vectorises (the same float operations per lane), then
  // the windows are read beam by beam.
  constexpr std::size_t kChunk = 64;
  alignas(16) float chunk_x[kChunk], chunk_y[kChunk];
  alignas(16) int chunk_ix[kChunk], chunk_iy[kChunk], chunk_valid[kChunk];
  const std::size_t beam_count = (scan.beams.size() + step - 1) / step;
  const BeamPoint* beams = scan.beams.data();
  for (std::size_t begin = 0; begin < beam_count; begin += kChunk) {
    const std::size_t count = std::min(kChunk, beam_count - begin);
    for (std::size_t k = 0; k < count; ++k) {
      const BeamPoint& beam = beams[(begin + k) * step];
      const float hx = px + c * beam.hit_x_m - s * beam.hit_y_m;
      const float hy = py + s * beam.hit_x_m + c * beam.hit_y_m;
      const float fx = hx * inv_res;
      const float fy = hy * inv_res;
      // Guard the float -> int conversion against absurd poses.
      const int valid = static_cast<int>(std::abs(fx) < 1e8f) & static_cast<int>(std::abs(fy) < 1e8f);
      chunk_x[k] = hx;
      chunk_y[k] = hy;
      const float safe_x = valid ? fx : 0.0f;
      const float safe_y = valid ? fy : 0.0f;
      const int ix = static_cast<int>(safe_x);
      const int iy = static_cast<int>(safe_y);
      chunk_ix[k] = ix - static_cast<int>(safe_x < static_cast<float>(ix));
      chunk_iy[k] = iy - static_cast<int>(safe_y < static_cast<float>(iy));
      chunk_valid[k] = valid;
    }
  for (std::size_t k = 0; k < count; ++k) {
    if (!chunk_valid[k]) {
      sums.miss();
      continue;
    }
    const float hx = chunk_x[k];
    const float hy = chunk_y[k];
    const int hix = chunk_ix[k];
    const int hiy = chunk_iy[k];
    float best_d2 = std::numeric_limits<float>::max();
    auto consider = [&](const Cell& hit) {
      const float ex = hit.mean_x_m - hx;
      const float ey = hit.mean_y_m - hy;
      float d2 = ex * ex + ey * ey;
      if (hit.normal_x != 0 || hit.normal_y != 0) {
        const float across = (ex * hit.normal_x + ey * hit.normal_y) * (1.0f / 127.0f);
        d2 = across * across + along_weight * (d2 - across * across);
      }
      if (d2 < best_d2) best_d2 = d2;
    };
    const int lx = hix & kMask;
    const int ly = hiy & kMask;
    if (lx >= 1 && lx < kTileSize - 1 && ly >= 1 && ly < kTileSize - 1) {
      // The window lies in one tile (most beams): one lookup, its mask's bits
      // name the occupied cells in row-major order (as the loops visit them).
      const Tile* tile = tile_at(hix >> kTileBits, hiy >> kTileBits);
      if (!tile) {
        sums.miss();
        continue;
      }
      const int corner = ((ly - 1) << kTileBits) + (lx - 1);
      for (std::uint64_t bits = (tile->occupied >> corner) & kWindow; bits != 0; bits &= bits - 1)
        consider(tile->cells[static_cast<std::size_t>(corner + std::countr_zero(bits))]);
    } else {
      // The window crosses tile borders: the (up to) 2 x 2 tiles it touches,
      // and per row and column of the window which tile and which cell.
      const int tx0 = (hix - 1) >> kTileBits;
      const int ty0 = (hiy - 1) >> kTileBits;
      const Tile* const tiles[2][2] = {{tile_at(tx0, ty0), tile_at(tx0 + 1, ty0)},
                                       {tile_at(tx0, ty0 + 1), tile_at(tx0 + 1, ty0 + 1)}};
      int column_tile[3], column_cell[3];
      for (int d = 0; d < 3; ++d) {
        column_tile[d] = ((hix - 1 + d) >> kTileBits) - tx0;
        column_cell[d] = (hix - 1 + d) & kMask;
      }
      for (int dy = 0; dy < 3; ++dy) {
        const int y = hiy - 1 + dy;
        const Tile* const* row = tiles[(y >> kTileBits) - ty0];
        const int row_cell = (y & kMask) << kTileBits;
        for (int dx = 0; dx < 3; ++dx) {
          const Tile* tile = row[column_tile[dx]];
          const int index = row_cell | column_cell[dx];
          if (tile && (tile->occupied >> index & 1)) consider(tile->cells[static_cast<std::size_t>(index)]);
        }
      }
    }
    sums.add(best_d2);
  }
  }
  return sums.result();
}

template <bool kWithScore>
PoseEvaluation CowGridMap::evaluate_terms(const Pose2& pose, const ScanPoints& scan) const {
  const float c = static_cast<float>(std::cos(pose.theta_rad));
  const float s = static_cast<float>(std::sin(pose.theta_rad));
  const float px = static_cast<float>(pose.x_m);
  const float py = static_cast<float>(pose.y_m);
  const float inv_res = static_cast<float>(inverse_resolution_);
  const int k = options_.kernel_radius_cells;
  const float along_weight = static_cast<float>(options_.along_line_weight);
  const bool check_free = options_.check_free_before_hit;
  const std::size_t step = static_cast<std::size_t>(std::max(1, options_.beam_step));
  BeamSums<kWithScore> sums(options_);
  for (std::size_t i = 0; i < scan.beams.size(); i += step) {
    const BeamPoint& beam = scan.beams[i];
    const float hx = px + c * beam.hit_x_m - s * beam.hit_y_m;
    const float hy = py + s * beam.hit_x_m + c * beam.hit_y_m;
    // Guard the float -> int conversion against absurd poses.
    if (!(std::abs(hx * inv_res) < 1e8f && std::abs(hy * inv_res) < 1e8f)) {
      sums.miss();
      continue;
    }
    const int hix = floor_to_int(hx * inv_res);
    const int hiy = floor_to_int(hy * inv_res);
    int fix = 0, fiy = 0;
    if (check_free) {
      const float fx = px + c * beam.free_x_m - s * beam.free_y_m;
      const float fy = py + s * beam.free_x_m + c * beam.free_y_m;
      if (!(std::abs(fx * inv_res) < 1e8f && std::abs(fy * inv_res) < 1e8f)) {
        sums.miss();
        continue;
      }
      fix = floor_to_int(fx * inv_res);
      fiy = floor_to_int(fy * inv_res);
    }
    float best_d2 = std::numeric_limits<float>::max();
    constexpr int kMask = kTileSize - 1;
    const Tile* hit_tile = nullptr;
    // Fast path: the whole window lies in one tile (most beams), one tile lookup.
    if ((hix & kMask) >= k && (hix & kMask) < kTileSize - k && (hiy & kMask) >= k &&
        (hiy & kMask) < kTileSize - k) {
      const int tx = (hix >> kTileBits) - tile_x0_;
      const int ty = (hiy >> kTileBits) - tile_y0_;
      if (static_cast<unsigned>(tx) >= static_cast<unsigned>(tiles_w_) ||
          static_cast<unsigned>(ty) >= static_cast<unsigned>(tiles_h_)) {
        sums.miss();
        continue;
      }
      hit_tile = tiles_[static_cast<std::size_t>(ty) * tiles_w_ + tx].get();
      if (!hit_tile) {
        sums.miss();
        continue;
      }
    }
    for (int dy = -k; dy <= k; ++dy) {
      for (int dx = -k; dx <= k; ++dx) {
        const Cell* hit =
            hit_tile ? &hit_tile->cells[(((hiy + dy) & kMask) << kTileBits) | ((hix + dx) & kMask)]
                     : cell(hix + dx, hiy + dy);
        if (!hit || hit->hits == 0) continue;
        // The cell just before the end point (same offset) must not be a wall:
        // a beam cannot end behind an obstacle it would have hit first.
        if (check_free) {
          const Cell* before = cell(fix + dx, fiy + dy);
          if (before && before->hits > 0) continue;
        }
        const float ex = hit->mean_x_m - hx;
        const float ey = hit->mean_y_m - hy;
        float d2 = ex * ex + ey * ey;
        if (hit->normal_x != 0 || hit->normal_y != 0) {
          const float across = (ex * hit->normal_x + ey * hit->normal_y) * (1.0f / 127.0f);
          d2 = across * across + along_weight * (d2 - across * across);
        }
        if (d2 < best_d2) best_d2 = d2;
      }
    }
    sums.add(best_d2);
  }
  return sums.result();
}

namespace {
// One bit per cell of a tile says which cells follow.
static_assert(CowGridMap::kTileSize * CowGridMap::kTileSize == 64);
// A tile table bigger than this is refused when read, whatever the options (a
// damaged size must not allocate gigabytes): 16 M slots, 1.6 km x 1.6 km of 5 cm cells.
constexpr std::uint64_t kMaxSlots = std::uint64_t{1} << 24;
}  // namespace

void CowGridMap::write_shared(archive::ByteWriter& out, const std::vector<const CowGridMap*>& maps) {
  // Distinct tiles in order of first use (maps in order, slots row-major), so
  // the same maps always give the same bytes.
  std::unordered_map<const Tile*, std::uint32_t> index;
  std::vector<const Tile*> distinct;
  for (const CowGridMap* map : maps)
    for (const auto& tile : map->tiles_)
      if (tile && index.emplace(tile.get(), static_cast<std::uint32_t>(distinct.size())).second)
        distinct.push_back(tile.get());
  out.put<std::uint64_t>(distinct.size());
  for (const Tile* tile : distinct) {
    std::uint64_t mask = 0;
    for (std::size_t i = 0; i < tile->cells.size(); ++i)
      if (tile->cells[i].hits != 0) mask |= std::uint64_t{1} << i;
    out.put<std::uint64_t>(mask);
    for (std::size_t i = 0; i < tile->cells.size(); ++i) {
      const Cell& c = tile->cells[i];
      if (c.hits == 0) continue;
      out.put<float>(c.mean_x_m);
      out.put<float>(c.mean_y_m);
      out.put<float>(tile->scatter[i].sxx);
      out.put<float>(tile->scatter[i].sxy);
      out.put<float>(tile->scatter[i].syy);
      out.put<std::int8_t>(c.normal_x);
      out.put<std::int8_t>(c.normal_y);
      out.put<std::uint16_t>(c.hits);
    }
  }
  out.put<std::uint64_t>(maps.size());
  for (const CowGridMap* map : maps) {
    out.put<std::int32_t>(map->tile_x0_);
    out.put<std::int32_t>(map->tile_y0_);
    out.put<std::int32_t>(map->tiles_w_);
    out.put<std::int32_t>(map->tiles_h_);
    out.put<std::uint64_t>(map->tile_count());
    for (std::size_t slot = 0; slot < map->tiles_.size(); ++slot) {
      if (!map->tiles_[slot]) continue;
      out.put<std::uint32_t>(static_cast<std::uint32_t>(slot));
      out.put<std::uint32_t>(index.at(map->tiles_[slot].get()));
    }
  }
}

std::vector<std::unique_ptr<CowGridMap>> CowGridMap::read_shared(archive::ByteReader& in,
                                                                 const CowGridMapOptions& options) {
  constexpr std::size_t kCellBytes = 5 * sizeof(float) + 2 * sizeof(std::int8_t) + sizeof(std::uint16_t);
  const std::uint64_t tile_count = in.get_count(sizeof(std::uint64_t));
  std::vector<std::shared_ptr<Tile>> distinct;
  distinct.reserve(tile_count);
  for (std::uint64_t t = 0; t < tile_count; ++t) {
    auto tile = std::make_shared<Tile>();
    const auto mask = in.get<std::uint64_t>();
    if (static_cast<std::size_t>(std::popcount(mask)) * kCellBytes > in.remaining())
      throw archive::ArchiveError("tile " + std::to_string(t) + " is cut short");
    for (std::size_t i = 0; i < tile->cells.size(); ++i) {
      if (!(mask >> i & 1)) continue;
      Cell& c = tile->cells[i];
      c.mean_x_m = in.get<float>();
      c.mean_y_m = in.get<float>();
      tile->scatter[i].sxx = in.get<float>();
      tile->scatter[i].sxy = in.get<float>();
      tile->scatter[i].syy = in.get<float>();
      c.normal_x = in.get<std::int8_t>();
      c.normal_y = in.get<std::int8_t>();
      c.hits = in.get<std::uint16_t>();
      if (c.hits == 0) throw archive::ArchiveError("tile " + std::to_string(t) + " lists a cell without hits");
    }
    tile->occupied = mask;
    distinct.push_back(std::move(tile));
  }
  const std::uint64_t map_count = in.get_count(4 * sizeof(std::int32_t) + sizeof(std::uint64_t));
  std::vector<std::unique_ptr<CowGridMap>> maps;
  maps.reserve(map_count);
  for (std::uint64_t m = 0; m < map_count; ++m) {
    auto map = std::make_unique<CowGridMap>(options);
    map->tile_x0_ = in.get<std::int32_t>();
    map->tile_y0_ = in.get<std::int32_t>();
    map->tiles_w_ = in.get<std::int32_t>();
    map->tiles_h_ = in.get<std::int32_t>();
    const std::string which = "map " + std::to_string(m);
    if (map->tiles_w_ < 0 || map->tiles_h_ < 0 || (map->tiles_w_ == 0) != (map->tiles_h_ == 0) ||
        map->tiles_w_ > map->max_tiles_per_axis_ || map->tiles_h_ > map->max_tiles_per_axis_ ||
        static_cast<std::uint64_t>(map->tiles_w_) * static_cast<std::uint64_t>(map->tiles_h_) > kMaxSlots)
      throw archive::ArchiveError(which + " has a tile table of " + std::to_string(map->tiles_w_) + " x " +
                                  std::to_string(map->tiles_h_));
    map->tiles_.resize(static_cast<std::size_t>(map->tiles_w_) * static_cast<std::size_t>(map->tiles_h_));
    const std::uint64_t held = in.get_count(2 * sizeof(std::uint32_t));
    std::int64_t previous_slot = -1;
    for (std::uint64_t k = 0; k < held; ++k) {
      const auto slot = in.get<std::uint32_t>();
      const auto tile = in.get<std::uint32_t>();
      // Slots ascend (as written): none out of the table, none twice.
      if (static_cast<std::int64_t>(slot) <= previous_slot || slot >= map->tiles_.size() || tile >= distinct.size())
        throw archive::ArchiveError(which + " refers to slot " + std::to_string(slot) + " / tile " +
                                    std::to_string(tile) + " of " + std::to_string(map->tiles_.size()) + " / " +
                                    std::to_string(distinct.size()));
      map->tiles_[slot] = distinct[tile];
      previous_slot = slot;
    }
    maps.push_back(std::move(map));
  }
  return maps;
}

}  // namespace pex::slam
