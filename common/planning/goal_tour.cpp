#include "planning/goal_tour.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pex::planning {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A move must gain more than this: no cycling on rounding.
constexpr double kMinGainM = 1e-9;

// Lengths over the reachable candidates only, renumbered 0..m-1; kStart and
// kEnd stand for the robot and the open end (every leg to kEnd costs 0).
class Legs {
 public:
  static constexpr int kStart = -1;
  static constexpr int kEnd = -2;

  Legs(const std::vector<double>& from_start, const std::vector<double>& between, const std::vector<int>& ids)
      : m_(ids.size()), start_(m_), between_(m_ * m_) {
    const std::size_t n = from_start.size();
    for (std::size_t i = 0; i < m_; ++i) {
      start_[i] = from_start[static_cast<std::size_t>(ids[i])];
      for (std::size_t j = 0; j < m_; ++j)
        between_[i * m_ + j] = between[static_cast<std::size_t>(ids[i]) * n + static_cast<std::size_t>(ids[j])];
    }
  }

  std::size_t size() const { return m_; }
  double operator()(int a, int b) const {
    if (b == kEnd) return 0.0;
    if (a == kStart) return start_[static_cast<std::size_t>(b)];
    return between_[static_cast<std::size_t>(a) * m_ + static_cast<std::size_t>(b)];
  }
  double length(const std::vector<int>& order) const {
    double sum = 0.0;
    int previous = kStart;
    for (const int c : order) {
      sum += (*this)(previous, c);
      previous = c;
    }
    return sum;
  }

 private:
  std::size_t m_;
  std::vector<double> start_;
  std::vector<double> between_;
};

std::vector<int> nearest_neighbour(const Legs& d) {
  const auto m = static_cast<int>(d.size());
  std::vector<int> order;
  std::vector<char> visited(d.size(), 0);
  int at = Legs::kStart;
  for (int step = 0; step < m; ++step) {
    int best = -1;
    for (int c = 0; c < m; ++c)
      if (!visited[static_cast<std::size_t>(c)] && (best < 0 || d(at, c) < d(at, best))) best = c;
    visited[static_cast<std::size_t>(best)] = 1;
    order.push_back(best);
    at = best;
  }
  return order;
}

// Cheapest insertion for an open path: repeatedly the candidate whose best
// insertion (between two neighbours, or at the open end) adds least.
std::vector<int> cheapest_insertion(const Legs& d) {
  const auto m = static_cast<int>(d.size());
  std::vector<int> order;
  std::vector<char> inserted(d.size(), 0);
  for (int step = 0; step < m; ++step) {
    int best_c = -1;
    std::size_t best_pos = 0;
    double best_cost = kInf;
    for (int c = 0; c < m; ++c) {
      if (inserted[static_cast<std::size_t>(c)]) continue;
      for (std::size_t pos = 0; pos <= order.size(); ++pos) {
        const int before = pos == 0 ? Legs::kStart : order[pos - 1];
        const int after = pos == order.size() ? Legs::kEnd : order[pos];
        const double cost = d(before, c) + d(c, after) - d(before, after);
        if (best_c < 0 || cost < best_cost) {
          best_c = c;
          best_pos = pos;
          best_cost = cost;
        }
      }
    }
    inserted[static_cast<std::size_t>(best_c)] = 1;
    order.insert(order.begin() + static_cast<std::ptrdiff_t>(best_pos), best_c);
  }
  return order;
}

// Optimal open path by dynamic programming over subsets (Held-Karp), run
// backwards so that ties go to the lower index at the first goal, the one
// that is driven: rest[mask][j] is the shortest path that starts at j (in
// mask) and visits every candidate not in mask.
std::vector<int> exact(const Legs& d) {
  const std::size_t m = d.size();
  if (m == 0) return {};
  const std::size_t full = (std::size_t{1} << m) - 1;
  std::vector<double> rest((full + 1) * m, kInf);
  std::vector<std::int8_t> next((full + 1) * m, -1);
  for (std::size_t j = 0; j < m; ++j) rest[full * m + j] = 0.0;
  for (std::size_t mask = full; mask-- > 1;) {
    for (std::size_t j = 0; j < m; ++j) {
      if (!(mask >> j & 1)) continue;
      double best = kInf;
      for (std::size_t k = 0; k < m; ++k) {
        if (mask >> k & 1) continue;
        const double length = d(static_cast<int>(j), static_cast<int>(k)) + rest[(mask | std::size_t{1} << k) * m + k];
        if (length < best) {
          best = length;
          next[mask * m + j] = static_cast<std::int8_t>(k);
        }
      }
      rest[mask * m + j] = best;
    }
  }
  std::size_t first = 0;
  for (std::size_t j = 1; j < m; ++j)
    if (d(Legs::kStart, static_cast<int>(j)) + rest[(std::size_t{1} << j) * m + j] <
        d(Legs::kStart, static_cast<int>(first)) + rest[(std::size_t{1} << first) * m + first])
      first = j;
  std::vector<int> order{static_cast<int>(first)};
  std::size_t mask = std::size_t{1} << first;
  for (std::size_t j = first; mask != full && next[mask * m + j] >= 0;) {
    j = static_cast<std::size_t>(next[mask * m + j]);
    order.push_back(static_cast<int>(j));
    mask |= std::size_t{1} << j;
  }
  // Only when the contract is broken (+inf between reachable candidates):
  // the rest in index order.
  for (std::size_t j = 0; j < m; ++j)
    if (!(mask >> j & 1)) order.push_back(static_cast<int>(j));
  return order;
}

// One pass of 2-opt: reverse order[i..j] when that shortens the path. On an
// open path only the legs into order[i] and out of order[j] change (none out
// when j is last); the legs inside keep their lengths (symmetric matrix).
int two_opt_pass(const Legs& d, std::vector<int>& order) {
  int moves = 0;
  const std::size_t m = order.size();
  for (std::size_t i = 0; i + 1 < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      const int before = i == 0 ? Legs::kStart : order[i - 1];
      const int after = j + 1 == m ? Legs::kEnd : order[j + 1];
      const double gain = d(before, order[i]) + d(order[j], after) - d(before, order[j]) - d(order[i], after);
      if (gain > kMinGainM) {
        std::reverse(order.begin() + static_cast<std::ptrdiff_t>(i), order.begin() + static_cast<std::ptrdiff_t>(j) + 1);
        ++moves;
      }
    }
  }
  return moves;
}

// One pass of Or-opt: move a run of 1 to 3 candidates, either way round, to
// the place where it adds least (between two others, right after the start,
// or at the open end), when that shortens the path.
int or_opt_pass(const Legs& d, std::vector<int>& order) {
  int moves = 0;
  const std::size_t m = order.size();
  for (std::size_t run = 1; run <= 3 && run < m; ++run) {
    for (std::size_t i = 0; i + run <= m; ++i) {
      const int first = order[i], last = order[i + run - 1];
      const int before = i == 0 ? Legs::kStart : order[i - 1];
      const int after = i + run == m ? Legs::kEnd : order[i + run];
      const double removed = d(before, first) + d(last, after) - d(before, after);
      // Best place among the legs (a, b) of the path without the run:
      // k = -1 is the leg from the start.
      double best_gain = kMinGainM;
      std::ptrdiff_t best_k = -2;
      bool best_reversed = false;
      for (std::ptrdiff_t k = -1; k < static_cast<std::ptrdiff_t>(m); ++k) {
        if (k >= static_cast<std::ptrdiff_t>(i) - 1 && k < static_cast<std::ptrdiff_t>(i + run)) continue;
        const int a = k < 0 ? Legs::kStart : order[static_cast<std::size_t>(k)];
        const int b = k + 1 == static_cast<std::ptrdiff_t>(m) ? Legs::kEnd : order[static_cast<std::size_t>(k + 1)];
        const double forward = d(a, first) + d(last, b) - d(a, b);
        const double backward = d(a, last) + d(first, b) - d(a, b);
        if (removed - forward > best_gain) {
          best_gain = removed - forward;
          best_k = k;
          best_reversed = false;
        }
        if (run > 1 && removed - backward > best_gain) {
          best_gain = removed - backward;
          best_k = k;
          best_reversed = true;
        }
      }
      if (best_k == -2) continue;
      std::vector<int> segment(order.begin() + static_cast<std::ptrdiff_t>(i),
                               order.begin() + static_cast<std::ptrdiff_t>(i + run));
      if (best_reversed) std::reverse(segment.begin(), segment.end());
      std::vector<int> rest;
      rest.reserve(m);
      for (std::size_t t = 0; t < m; ++t)
        if (t < i || t >= i + run) rest.push_back(order[t]);
      // Where leg k of the original numbering is in `rest`: the run's
      // place closed up, so legs after it move back by `run`.
      const std::ptrdiff_t at = (best_k < static_cast<std::ptrdiff_t>(i) ? best_k : best_k - static_cast<std::ptrdiff_t>(run)) + 1;
      rest.insert(rest.begin() + at, segment.begin(), segment.end());
      order = std::move(rest);
      ++moves;
    }
  }
  return moves;
}

}  // namespace

double open_tour_length(const std::vector<double>& from_start_m, const std::vector<double>& between_m,
                        const std::vector<int>& order) {
  const std::size_t n = from_start_m.size();
  double sum = 0.0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const auto c = static_cast<std::size_t>(order[k]);
    sum += k == 0 ? from_start_m[c] : between_m[static_cast<std::size_t>(order[k - 1]) * n + c];
  }
  return sum;
}

namespace {

// The reachable candidates (ids ascending) and the unreachable ones.
void split(const std::vector<double>& from_start_m, std::vector<int>& reachable, std::vector<int>& unreachable) {
  for (std::size_t i = 0; i < from_start_m.size(); ++i)
    (std::isfinite(from_start_m[i]) ? reachable : unreachable).push_back(static_cast<int>(i));
}

void to_ids(std::vector<int>& order, const std::vector<int>& ids) {
  for (auto& c : order) c = ids[static_cast<std::size_t>(c)];
}

}  // namespace

OpenTour nearest_neighbour_tour(const std::vector<double>& from_start_m, const std::vector<double>& between_m) {
  OpenTour tour;
  std::vector<int> ids;
  split(from_start_m, ids, tour.unreachable);
  const Legs legs(from_start_m, between_m, ids);
  tour.order = nearest_neighbour(legs);
  tour.length_m = legs.length(tour.order);
  to_ids(tour.order, ids);
  return tour;
}

OpenTour solve_open_tour(const std::vector<double>& from_start_m, const std::vector<double>& between_m,
                         const TourOptions& options) {
  OpenTour tour;
  std::vector<int> ids;
  split(from_start_m, ids, tour.unreachable);
  const Legs legs(from_start_m, between_m, ids);
  const auto exact_max = static_cast<std::size_t>(std::clamp(options.exact_max_candidates, 0, 16));
  if (ids.size() <= exact_max) {
    tour.order = exact(legs);
    tour.optimal = true;
  } else {
    auto greedy = nearest_neighbour(legs);
    auto inserted = cheapest_insertion(legs);
    tour.order = legs.length(inserted) < legs.length(greedy) ? std::move(inserted) : std::move(greedy);
    while (tour.passes < options.max_passes) {
      ++tour.passes;
      const int moves = two_opt_pass(legs, tour.order) + or_opt_pass(legs, tour.order);
      tour.improving_moves += moves;
      if (moves == 0) break;
    }
  }
  tour.length_m = legs.length(tour.order);
  to_ids(tour.order, ids);
  return tour;
}

}  // namespace pex::planning
