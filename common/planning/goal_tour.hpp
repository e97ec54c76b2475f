#pragma once
// The order in which to visit all goal candidates: the shortest open path
// that starts at the robot and visits every reachable candidate once (Kulich,
// Kubalík, Přeučil, Sensors 2019; Kulich et al., ICRA 2011, "distance
// utility"). The first candidate of the order is the next goal.
//
// Why an open path and not a tour back to the start: exploration ends
// wherever the last frontier is, the robot never drives back. A closed tour
// would count a return leg that is not driven, and that leg pulls the order
// towards finishing near the robot, i.e. towards first going to far goals
// that are cheap to come back from. A closed tour whose legs back to the
// start cost nothing is the same problem as this open path.
//
// Pure and deterministic: no clock, no random numbers; effort is bounded by
// counts (subset size for the exact solver, passes for the heuristic).
#include <cstddef>
#include <vector>

#include "planning/path_matrix.hpp"

namespace pex::planning {

struct TourOptions {
  // Up to this many reachable candidates the order is optimal: dynamic
  // programming over subsets, 2^n n^2 steps (n = 12: 0.6 M). Clamped to 16.
  int exact_max_candidates = 12;
  // Above that: the shorter of nearest neighbour and cheapest insertion,
  // improved by 2-opt and Or-opt moves (segments of 1 to 3 candidates moved,
  // either way round) until a pass improves nothing, at most this many
  // passes. A pass tries every move once and applies each that shortens the
  // path by more than 1e-9 m.
  int max_passes = 50;
  // The tour runs over the this many candidates nearest by path only (0: over
  // all). Exploration moves its frontiers as it goes: most goals are seen from
  // the way before they are reached, and far candidates are gone or elsewhere
  // by the time the robot gets near, so the order among them is guesswork that
  // still pulls the first goal. A receding horizon plans the order where it
  // will hold. With a horizon the plan also needs the paths among those
  // candidates only (shortest_paths_among_nearest), not the whole matrix:
  // plan time then no longer grows with the square of the map's corners.
  int horizon_candidates = 0;
  // The tour's first candidate is the goal only when its path costs at most
  // max_first_leg_ratio times the nearest candidate's plus first_leg_slack_m;
  // else the nearest is (plan_exploration; <= 0: no bound, the pure tour).
  // Where frontiers recede as the robot drives (open ground: every goal is
  // seen before it is reached) the order beyond the nearest candidates is
  // guesswork, and a pure tour sent the robot back and forth (campus: 1.43
  // times greedy's path); what a tour is for is the leftover near the robot
  // that greedy leaves for a trip back (a corner of the room it is leaving).
  // Figures: docs/exploration.md, "The bounded tour".
  double max_first_leg_ratio = 1.5;
  double first_leg_slack_m = 2.0;
  // The tour visits one candidate per frontier chain (the cheapest to reach
  // from the robot), as a generalised TSP visits one goal per frontier
  // cluster (Kulich, Kubalík, Přeučil 2019): seeing a chain from one of its
  // candidates sees the rest of it, so the others are no stops of their own.
  bool one_per_chain = false;
};

struct OpenTour {
  std::vector<int> order;        // reachable candidates, in visiting order
  double length_m = 0.0;         // start -> order[0] -> ... -> order.back()
  std::vector<int> unreachable;  // candidates at +inf from the start, ascending
  bool optimal = false;          // found by the exact solver
  int improving_moves = 0;       // moves the heuristic applied
  int passes = 0;                // passes the heuristic made
};

// `from_start_m[i]`: path length from the robot to candidate i (+inf: not
// reachable, left out of the order); `between_m`: n x n row-major lengths
// between candidates, symmetric (the moves reverse segments), finite between
// candidates reachable from the start (as a PathMatrix is: both in the
// start's piece of the C-space). Deterministic; among optimal orders the
// exact solver takes the one whose first goal has the lowest index.
OpenTour solve_open_tour(const std::vector<double>& from_start_m, const std::vector<double>& between_m,
                         const TourOptions& options = {});
inline OpenTour solve_open_tour(const PathMatrix& matrix, const TourOptions& options = {}) {
  return solve_open_tour(matrix.from_start_m, matrix.between_m, options);
}

// The greedy baseline: from the robot always to the nearest candidate not yet
// visited. Its first candidate is the paper's goal (the nearest by path).
OpenTour nearest_neighbour_tour(const std::vector<double>& from_start_m, const std::vector<double>& between_m);

// Length of the open path start -> order[0] -> ... (0 for an empty order).
double open_tour_length(const std::vector<double>& from_start_m, const std::vector<double>& between_m,
                        const std::vector<int>& order);

}  // namespace pex::planning
