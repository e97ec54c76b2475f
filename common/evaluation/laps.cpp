#include "evaluation/laps.hpp"

#include <algorithm>
#include <stdexcept>

namespace pex::evaluation {

double LapTiming::map(double t_s, int lap) const {
  const double start = first_s + lap * (last_s - first_s + gap_s);
  return lap % 2 == 0 ? start + (t_s - first_s) : start + (last_s - t_s);
}

LapTiming lap_timing(const CarmenLog& log, double gap_s) {
  LapTiming timing;
  timing.gap_s = gap_s;
  if (log.lasers.empty()) return timing;
  // FLASER stamps run backwards at times (Intel's by up to 0.6 s): the
  // earliest and latest, not the first and last lines'.
  const auto [lo, hi] = std::minmax_element(log.lasers.begin(), log.lasers.end(),
                                            [](const CarmenLaser& a, const CarmenLaser& b) {
                                              return a.timestamp_s < b.timestamp_s;
                                            });
  timing.first_s = lo->timestamp_s;
  timing.last_s = hi->timestamp_s;
  return timing;
}

CarmenLog lap_log(const CarmenLog& log, int laps, double gap_s) {
  if (laps < 1) throw std::invalid_argument("laps must be at least 1");
  if (!(gap_s >= 0.0)) throw std::invalid_argument("the gap between laps must be >= 0 s");
  if (laps == 1) return log;
  const LapTiming timing = lap_timing(log, gap_s);
  CarmenLog out;
  out.malformed_lines = log.malformed_lines;
  out.first_error = log.first_error;
  const std::size_t n = log.lasers.size();
  out.lasers.reserve(n * static_cast<std::size_t>(laps));
  out.order.reserve(n * static_cast<std::size_t>(laps));
  for (int lap = 0; lap < laps; ++lap) {
    for (std::size_t i = 0; i < n; ++i) {
      CarmenLaser laser = log.lasers[lap % 2 == 0 ? i : n - 1 - i];
      laser.timestamp_s = timing.map(laser.timestamp_s, lap);
      out.order.push_back({true, out.lasers.size()});
      out.lasers.push_back(std::move(laser));
    }
  }
  return out;
}

std::vector<Relation> lap_relations(const std::vector<Relation>& relations, const LapTiming& timing, int laps) {
  std::vector<Relation> out;
  out.reserve(relations.size() * static_cast<std::size_t>(std::max(laps, 0)));
  for (int lap = 0; lap < laps; ++lap)
    for (const Relation& r : relations) {
      Relation copy = r;
      copy.t1_s = timing.map(r.t1_s, lap);
      copy.t2_s = timing.map(r.t2_s, lap);
      out.push_back(copy);
    }
  return out;
}

}  // namespace pex::evaluation
