#pragma once
// Which beams of the laser are blind. A beam without a return that runs into
// a wall the map holds (known_walls.hpp) saw nothing where something stands:
// glass or a dark surface at a grazing angle now and then, but the same beam
// doing so scan after scan, with no return in between, is a laser that cannot
// see there (part of its window covered: a cable, mud, a hand). Stopping such
// a beam at the walls the map holds keeps those walls, but a wall the map has
// not seen yet is not known: the beam would still give free space through it
// for free_range_m, and the planner would send the robot into that wall (the
// sector fault: a pillar's unseen side carved away, the robot against it). A
// blind beam tells nothing, so it gives no free space at all until it returns
// an echo again. Pure: no clock, no I/O.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "mapping/known_walls.hpp"

namespace pex::mapping {

struct BlindBeamOptions {
  // A beam is blind once it had no return at a wall the map holds in this
  // many of its scans with no return in between (0: never; a return clears it).
  int after_stopped_scans = 2;
  // A beam that has not returned an echo since the first scan observed gives
  // no free space either. A sector blind from the start (the window covered
  // when the robot boots, or a mapper restarted while it stays covered) has
  // no wall the map holds to be found blind against, and its beams would
  // carve free_range_m through the walls about the start; a laser that sees
  // has every beam return within the first turns of the robot.
  bool no_free_space_before_first_echo = true;
};

class BlindBeams {
 public:
  explicit BlindBeams(BlindBeamOptions options = {}) : options_(options) {}

  // One scan (`ranges`, returns as is_return takes them) and its beams'
  // extents against the map (NoReturnExtents::extent_m: empty when no beam
  // ran into a wall, else a beam stopped short of free_range_m ran into one).
  // A scan of another beam count starts afresh.
  void observe(std::span<const float> ranges, double range_min_m, double range_max_m,
               std::span<const float> stopped_extent_m, double free_range_m);

  // The extents scan_to_polygon takes for `ranges`: `stopped_extent_m` (or
  // free_range_m where it is empty), with every blind beam's at the minimum
  // range, so it gives no free space. Empty when no beam is stopped or blind
  // (scan_to_polygon's "none").
  std::vector<float> extents(std::span<const float> ranges, double range_min_m, double range_max_m,
                             std::span<const float> stopped_extent_m, double free_range_m) const;

  bool blind(std::size_t beam) const { return beam < blind_.size() && blind_[beam] != 0; }
  // Per beam of the last scan observed: 1 blind, 0 not.
  std::span<const std::uint8_t> mask() const { return blind_; }
  // Per beam: 1 where a beam without a return gives no free space (blind, or
  // no echo yet with no_free_space_before_first_echo), 0 where it does. What
  // extents() applies, for callers that make the polygon themselves.
  std::span<const std::uint8_t> no_free_space_mask() const { return no_free_space_; }
  // Beams that have not returned an echo yet (no_free_space_before_first_echo).
  int never_echoed() const { return never_echoed_; }
  int count() const { return count_; }  // blind beams now
  // Scans after which some beam was blind when none was before.
  std::int64_t onsets() const { return onsets_; }

 private:
  BlindBeamOptions options_;
  std::vector<std::uint16_t> stopped_runs_;  // per beam: stopped scans since its last return
  std::vector<std::uint8_t> blind_;
  std::vector<std::uint8_t> echoed_;         // per beam: returned an echo since the first scan
  std::vector<std::uint8_t> no_free_space_;  // blind_, or not echoed_ (with the option)
  int count_ = 0;
  int never_echoed_ = 0;
  std::int64_t onsets_ = 0;
};

// Adjacent blind beams of a mask (BlindBeams::mask), first and last beam
// index of each run, in beam order: where the laser cannot see, for the
// operator (the mapper's DEGRADED reason says it in radians).
struct BeamRun {
  std::size_t first = 0;
  std::size_t last = 0;
};
std::vector<BeamRun> blind_runs(std::span<const std::uint8_t> blind);

// What BlindBeams::extents gives, for a mask of blind beams (one value per
// beam of `ranges`, or empty: none blind): the extents scan_to_polygon takes.
std::vector<float> without_blind_beams(std::span<const float> ranges, double range_min_m, double range_max_m,
                                       std::span<const float> stopped_extent_m, double free_range_m,
                                       std::span<const std::uint8_t> blind);

}  // namespace pex::mapping
