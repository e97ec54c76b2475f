#include "mapping/blind_beams.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mapping/scan_polygon.hpp"

namespace pex::mapping {
namespace {

// Where a blind beam's free space ends: scan_to_polygon takes an extent
// above 0 only, and nothing is known nearer than the minimum range anyway.
constexpr double kLeastExtentM = 0.01;

// Compared in float, as the extents are kept: free_range_m itself (not
// stopped) may round below its double.
bool stopped_at_wall(std::span<const float> extent_m, std::size_t i, double free_range_m) {
  return i < extent_m.size() && std::isfinite(extent_m[i]) && extent_m[i] < static_cast<float>(free_range_m);
}

}  // namespace

void BlindBeams::observe(std::span<const float> ranges, double range_min_m, double range_max_m,
                         std::span<const float> stopped_extent_m, double free_range_m) {
  if (ranges.size() != blind_.size()) {
    stopped_runs_.assign(ranges.size(), 0);
    blind_.assign(ranges.size(), 0);
    echoed_.assign(ranges.size(), 0);
    no_free_space_.assign(ranges.size(), 0);
    count_ = 0;
  }
  const int count_before = count_;
  const auto needed = static_cast<std::uint16_t>(
      std::clamp<int>(options_.after_stopped_scans, 0, std::numeric_limits<std::uint16_t>::max()));
  never_echoed_ = 0;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    if (is_return(ranges[i], range_min_m, range_max_m)) {
      echoed_[i] = 1;
      stopped_runs_[i] = 0;
      count_ -= blind_[i];
      blind_[i] = 0;
    } else if (needed > 0 && stopped_at_wall(stopped_extent_m, i, free_range_m)) {
      // A beam without a return into open space is no evidence either way:
      // only one that missed a wall the map holds counts.
      if (stopped_runs_[i] < needed) ++stopped_runs_[i];
      if (stopped_runs_[i] >= needed && !blind_[i]) {
        blind_[i] = 1;
        ++count_;
      }
    }
    const bool unproven = options_.no_free_space_before_first_echo && !echoed_[i];
    never_echoed_ += unproven ? 1 : 0;
    no_free_space_[i] = blind_[i] || unproven;
  }
  if (count_before == 0 && count_ > 0) ++onsets_;
}

std::vector<float> BlindBeams::extents(std::span<const float> ranges, double range_min_m, double range_max_m,
                                       std::span<const float> stopped_extent_m, double free_range_m) const {
  if (count_ == 0 && never_echoed_ == 0) return {stopped_extent_m.begin(), stopped_extent_m.end()};
  return without_blind_beams(ranges, range_min_m, range_max_m, stopped_extent_m, free_range_m, no_free_space_);
}

std::vector<float> without_blind_beams(std::span<const float> ranges, double range_min_m, double range_max_m,
                                       std::span<const float> stopped_extent_m, double free_range_m,
                                       std::span<const std::uint8_t> blind) {
  std::vector<float> out(stopped_extent_m.begin(), stopped_extent_m.end());
  const double least = std::max(range_min_m, kLeastExtentM);
  if (blind.size() != ranges.size() || !(least < free_range_m) ||
      std::find(blind.begin(), blind.end(), std::uint8_t{1}) == blind.end())
    return out;
  // No beam stopped: the others keep their free range (infinite is "not stopped").
  if (out.size() != ranges.size()) out.assign(ranges.size(), std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < ranges.size(); ++i)
    if (blind[i] && !is_return(ranges[i], range_min_m, range_max_m)) out[i] = static_cast<float>(least);
  return out;
}

std::vector<BeamRun> blind_runs(std::span<const std::uint8_t> blind) {
  std::vector<BeamRun> runs;
  for (std::size_t i = 0; i < blind.size(); ++i) {
    if (!blind[i]) continue;
    if (!runs.empty() && runs.back().last + 1 == i)
      runs.back().last = i;
    else
      runs.push_back({i, i});
  }
  return runs;
}

}  // namespace pex::mapping
