#pragma once
// GMapping's per-particle map: a grid whose cells accumulate the laser end
// points that fell in them (hit count and their mean position, which gives the
// matcher sub-cell precision). Cells live in square tiles held by shared
// pointers; a copy shares every tile and a write clones only the tile it
// touches while shared (copy-on-write), so 30 particles that descend from a
// common ancestor cost one map plus the tiles where they differ.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "slam/particle_map.hpp"

namespace pex::archive {
class ByteReader;
class ByteWriter;
}  // namespace pex::archive

namespace pex::slam {

struct CowGridMapOptions {
  double resolution_m = 0.05;
  // The matcher looks for the nearest occupied cell within this many cells of
  // a beam's end point (1 = a 3x3 window).
  int kernel_radius_cells = 1;
  // Score per beam: exp(-d^2 / score_sigma_m2), d = distance from the end point
  // to the nearest occupied cell's mean hit position (GMapping's `sigma`, whose
  // usual 0.05 m^2 is nearly flat over a 3x3 window of 5 cm cells, so the climb
  // wanders on plateaus). About the squared cell size keeps a slope everywhere
  // in the window.
  double score_sigma_m2 = 0.002;
  // Log-likelihood per beam: -d^2 / likelihood_sigma_m2 when a cell matched,
  // null_log_likelihood / likelihood_sigma_m2 when none did (GMapping's
  // `lsigma` and `nullLikelihood`).
  double likelihood_sigma_m2 = 0.075;
  double null_log_likelihood = -0.5;
  // Reject a candidate cell when the cell at the same offset from the point
  // just before the end point is occupied too (a beam cannot end behind a
  // wall). Grazing beams then lose their match on the very wall they hit, which
  // biases the heading, so it is off by default.
  bool check_free_before_hit = false;
  // Only every beam_step-th beam is scored (1 = all).
  int beam_step = 1;
  // Where a cell's hits lie on a line (a wall), the distance of an end point to
  // the cell counts its part along the line with this weight (point-to-line
  // matching). A sparse map of end points otherwise pulls each new scan back
  // towards the pose the map was seen from, most in corridors.
  double along_line_weight = 0.1;
  // Hits on a line: the smaller scatter eigenvalue at most this fraction of the larger.
  double line_flatness = 0.1;
  // The map's width and height at most this (m), measured on its tile table
  // (the tiles written and a margin of up to 8 tiles the table grows by): end
  // points that would make it wider are left out (counted by insert). The tile table is dense, one
  // 16-byte slot per tile of 8 x 8 cells, per particle: at 5 cm cells 400 m is
  // at most 16 MB a map. Without a bound one pose far away (a bad odometry
  // reading) asked for 128 GB.
  double max_extent_m = 400.0;
  // Tiles along each axis that max_extent_m allows (at least 1).
  int max_tiles_per_axis() const;
};

class CowGridMap final : public ParticleMap {
 public:
  static constexpr int kTileBits = 3;
  static constexpr int kTileSize = 1 << kTileBits;

  // What the matcher reads of a cell (12 bytes: a 3x3 window's row is 36
  // contiguous bytes, mostly one cache line).
  struct Cell {
    float mean_x_m = 0.0f;
    float mean_y_m = 0.0f;
    // Unit normal of the line the hits lie on, times 127; (0, 0) while they
    // do not (yet) form a line. 8 bits are plenty for weighting distances.
    std::int8_t normal_x = 0, normal_y = 0;
    std::uint16_t hits = 0;  // saturates
  };
  // What only insertion reads: the scatter of the hits about their mean
  // (sums of squared deviations, m^2), from which the normal is derived.
  struct Scatter {
    float sxx = 0.0f, sxy = 0.0f, syy = 0.0f;
  };
  struct Tile {
    std::array<Cell, kTileSize * kTileSize> cells{};
    std::array<Scatter, kTileSize * kTileSize> scatter{};
    // Bit (y << kTileBits | x) set: that cell has hits. The matcher reads a
    // 3x3 window of cells per beam, most of them empty (a wall crosses a
    // window in a line): the mask finds the occupied ones without touching
    // the others.
    std::uint64_t occupied = 0;
  };

  explicit CowGridMap(const CowGridMapOptions& options);

  std::unique_ptr<ParticleMap> clone() const override;
  // Returns the end points left out: beyond options().max_extent_m.
  std::size_t insert(const Pose2& robot_pose, const ScanPoints& scan) override;
  PoseEvaluation evaluate(const Pose2& robot_pose, const ScanPoints& scan) const override;
  // The likelihood alone: no exp() per beam for the score.
  double log_likelihood(const Pose2& robot_pose, const ScanPoints& scan) const override;
  std::size_t referenced_bytes() const override;
  // evaluate() through the general window (any kernel radius, the free-cell
  // test), which the shipped window's unrolled path must equal bit for bit.
  PoseEvaluation evaluate_general(const Pose2& robot_pose, const ScanPoints& scan) const {
    return evaluate_terms<true>(robot_pose, scan);
  }

  // The cell containing world point (x, y), or nullptr when never written.
  const Cell* cell_at(double x_m, double y_m) const;
  std::size_t tile_count() const;
  // The tiles this map holds, in slot order (row-major): maps that share a
  // tile hold the same pointer, so the distinct pointers over a set of maps
  // are the memory that set really uses.
  std::vector<const Tile*> tiles() const;
  const CowGridMapOptions& options() const { return options_; }

  // Checkpoints (archive/byte_archive.hpp) of maps that share tiles, as the
  // particles' maps do: every distinct tile is written once (its cells with
  // hits only; a cell without hits was never written, so it is all zeros) and
  // every map as its tile table referring to them, in a deterministic order.
  static void write_shared(archive::ByteWriter& out, const std::vector<const CowGridMap*>& maps);
  // The maps written by write_shared, with `options` (the configuration's;
  // the caller checks they are the saved maps'). Tiles are shared exactly as
  // they were: a restored set of maps takes the memory the saved one took, and
  // copies on write where it would have. Throws archive::ArchiveError for
  // anything malformed (an index out of range, a cell without hits).
  static std::vector<std::unique_ptr<CowGridMap>> read_shared(archive::ByteReader& in,
                                                              const CowGridMapOptions& options);

 private:
  const Cell* cell(int ix, int iy) const {
    const int tx = (ix >> kTileBits) - tile_x0_;
    const int ty = (iy >> kTileBits) - tile_y0_;
    if (static_cast<unsigned>(tx) >= static_cast<unsigned>(tiles_w_) ||
        static_cast<unsigned>(ty) >= static_cast<unsigned>(tiles_h_))
      return nullptr;
    const Tile* tile = tiles_[static_cast<std::size_t>(ty) * tiles_w_ + tx].get();
    if (!tile) return nullptr;
    return &tile->cells[((iy & (kTileSize - 1)) << kTileBits) | (ix & (kTileSize - 1))];
  }
  template <bool kWithScore>
  PoseEvaluation evaluate_terms(const Pose2& robot_pose, const ScanPoints& scan) const;
  // The same for the shipped window (kernel_radius_cells 1, no free-cell
  // test), unrolled and led by the tiles' occupancy masks: the same terms,
  // bit for bit, in about half the instructions.
  template <bool kWithScore>
  PoseEvaluation evaluate_window3(const Pose2& robot_pose, const ScanPoints& scan) const;
  const Tile* tile_at(int tx, int ty) const {
    tx -= tile_x0_;
    ty -= tile_y0_;
    if (static_cast<unsigned>(tx) >= static_cast<unsigned>(tiles_w_) ||
        static_cast<unsigned>(ty) >= static_cast<unsigned>(tiles_h_))
      return nullptr;
    return tiles_[static_cast<std::size_t>(ty) * tiles_w_ + tx].get();
  }
  // The tile holding cell (ix, iy), made and copied on write as needed, with
  // the cell marked occupied (the caller adds a hit); `index` is the cell's.
  // nullptr: the cell lies beyond the map's extent.
  Tile* mutable_tile(int ix, int iy, int& index);
  void update_normal(Cell& cell, const Scatter& scatter) const;
  // false: including tile (tx, ty) would make the table wider or higher than
  // max_tiles_per_axis_; nothing changed.
  bool grow_to_include(int tx, int ty);

  CowGridMapOptions options_;
  double inverse_resolution_;
  int max_tiles_per_axis_;
  int tile_x0_ = 0, tile_y0_ = 0, tiles_w_ = 0, tiles_h_ = 0;
  std::vector<std::shared_ptr<Tile>> tiles_;  // row-major, tiles_h_ x tiles_w_
};

}  // namespace pex::slam
