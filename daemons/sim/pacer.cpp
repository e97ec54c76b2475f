#include "pacer.hpp"

#include <algorithm>

namespace pex::simd {

Pacer::Pacer(PacingOptions options) : options_(std::move(options)), channels_(options_.channels.size()) {}

void Pacer::on_stamp(std::size_t index, std::int64_t stamp_us, double wall_s) {
  if (index >= channels_.size()) return;
  Channel& c = channels_[index];
  // A stamp never moves back (a restarted daemon's first messages may be older).
  c.stamp_us = c.heard ? std::max(c.stamp_us, stamp_us) : stamp_us;
  c.heard = true;
  c.wall_s = wall_s;
}

std::string Pacer::holding(std::int64_t sim_utime_us, double wall_s) const {
  if (options_.max_lag_us <= 0) return {};
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    const Channel& c = channels_[i];
    if (!c.heard || wall_s - c.wall_s > options_.silence_wall_s) continue;
    const std::int64_t period = i < options_.periods_us.size() ? options_.periods_us[i] : 0;
    if (sim_utime_us - c.stamp_us > options_.max_lag_us + period) return options_.channels[i];
  }
  return {};
}

bool Pacer::may_advance(std::int64_t sim_utime_us, double wall_s) const {
  return holding(sim_utime_us, wall_s).empty();
}

}  // namespace pex::simd
