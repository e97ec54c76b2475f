#pragma once
// All the path lengths a tour over goal candidates needs: from the robot to
// every candidate and between every pair of candidates, in the same exact
// shortest-path metric as shortest_paths (visibility_graph.hpp): polylines in
// the C-space that bend only at its reflex vertices (moved interior_offset_m
// inward).
//
// How (and why it is fast): the graph over the reflex vertices is built once,
// with only the edges a shortest path can use. A shortest path bends around a
// reflex vertex only along a line tangent to the boundary there; an edge
// whose line runs on behind its reflex end into the obstacle would bend with
// the obstacle outside the bend, and is dropped before any segment test (with
// a slack for the nodes' offset from the vertices, so that the lengths stay
// those of shortest_paths' graph). Each candidate and the start are joined to
// the reflex vertices they see the same way; one Dijkstra per candidate over
// this sparse graph gives the lengths that bend, for the pairs that do not
// see each other along a straight segment.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "planning/cspace.hpp"
#include "planning/pruned_graph.hpp"

namespace pex::planning {

struct PathMatrixOptions {
  // Drop graph edges that cannot be on a shortest path before testing them
  // (see above). false: every visible pair is an edge (tests compare).
  bool tangent_pruning = true;
  // false: only the lengths and paths from the start, between_m is left
  // empty (what the greedy strategy needs, over the same sparse graph).
  bool between_targets = true;
  // > 0: between the this-many targets nearest the start by path only (ties:
  // the lower index), of those `between_choice` marks (empty: every target),
  // listed nearest first in PathMatrix::nearest; the other pairs stay +inf
  // and cost no search. 0: between every pair.
  std::size_t between_nearest = 0;
  std::vector<char> between_choice{};
};

struct PathMatrix {
  // Per target i: length of the shortest path from the start (+inf if not
  // reachable), and the path itself (start first, target last; empty if not
  // reachable).
  std::vector<double> from_start_m;
  std::vector<std::vector<Point>> path_from_start;
  // n x n, row-major: between_m[i * n + j] is the length of the shortest path
  // between targets i and j. Exactly symmetric, 0 on the diagonal, +inf when
  // the targets lie in different connected pieces of the C-space. Empty when
  // not asked for (PathMatrixOptions::between_targets).
  std::vector<double> between_m;

  // Statistics.
  std::int64_t reflex_nodes = 0;
  std::int64_t graph_edges = 0;    // undirected edges of the sparse graph
  std::int64_t segment_tests = 0;  // visibility tests made
  // false: shortest_paths_to_cheapest stopped before it settled every
  // target; a +inf in from_start_m may then be a target it did not search.
  bool all_searched = true;
  // shortest_paths_among_nearest, or PathMatrixOptions::between_nearest: the
  // targets between_m holds, nearest first.
  std::vector<int> nearest;

  std::size_t size() const { return from_start_m.size(); }
  double between(std::size_t i, std::size_t j) const { return between_m[i * size() + j]; }
};

// Contract as shortest_paths: `start` and every target should lie in the
// C-space's interior (ConfigurationSpace::nearest_interior_point); targets
// are path ends, never intermediate nodes. from_start_m agrees with
// shortest_paths(cspace, start, targets).length_m (up to rounding of the sums).
// Pure and deterministic: ties go to the lower node index.
// `cache` (may be null) keeps the graph's segment tests for the next call
// (VisibilityCache); the result does not depend on it.
PathMatrix shortest_path_matrix(const ConfigurationSpace& cspace, const Point& start,
                                const std::vector<Point>& targets, const PathMatrixOptions& options = {},
                                VisibilityCache* cache = nullptr);

// What a greedy choice needs of the start's row, without the whole graph.
// `cost(i, length_m, path)` is target i's cost once its shortest path (start
// first) is known; it must be at least length_m, or +inf for a target that is
// no choice (blacklisted). `required[i]` (empty: none) marks targets whose
// path is wanted whatever their cost (the goal the robot follows).
struct CheapestTargetQuery {
  std::function<double(std::size_t target, double length_m, const std::vector<Point>& path)> cost;
  std::vector<char> required;
  // Per target: may it be chosen (cost not always +inf)? Empty: every target.
  // Only steers the search (A*'s lower bound aims at these and the required);
  // with no choice and no required target nothing is searched.
  std::vector<char> choice;
};

// A search from `start` over the same graph as shortest_path_matrix (same
// pruning, same lengths), but lazy: the edges of a node are tested only when
// it is settled, and only those that would improve a tentative distance; A*,
// with the straight-line distance to the nearest target it aims at (`choice`
// and `required`) as the lower bound. It stops once every required target is
// settled and every path left, by that bound, is longer than the least cost
// of a settled target: no target left can cost less. The
// targets settled by then have their lengths and paths in from_start_m /
// path_from_start, the others +inf and no path (not searched, whether
// reachable or not: ConfigurationSpace::piece_of tells). between_m is empty.
// On an open map it settles a few nodes of hundreds, those towards the
// cheapest target (docs/exploration.md, "Planning time"). Where it would
// settle more than a tenth of the reflex nodes (a ragged map), it gives up
// for shortest_path_matrix's row from the start instead (between_targets
// false): every target's length and path, all_searched, the same lengths.
// Pure and deterministic. `cache` as for shortest_path_matrix.
PathMatrix shortest_paths_to_cheapest(const ConfigurationSpace& cspace, const Point& start,
                                      const std::vector<Point>& targets, const CheapestTargetQuery& query,
                                      VisibilityCache* cache = nullptr);

struct NearestTargetsQuery {
  std::size_t count = 10;  // how many of the `choice` targets, nearest by path length
  // Per target: may it be one of them? Empty: every target.
  std::vector<char> choice;
  // Per target: its path from the start is wanted, nearest or not.
  std::vector<char> required;
};

// What a tour over the nearest candidates needs, searched lazily as
// shortest_paths_to_cheapest searches: from the start until the `count`
// nearest choice targets (ties: the lower node index; `nearest`, in order)
// and every required one are settled, then between those nearest only (the
// straight segment where it is free, else a lazy search from each for the
// later ones it does not see); where that would cost more than the whole
// matrix (the search from the start settles a tenth of the reflex nodes,
// or the searches between would test more pairs than the pruned graph has),
// from shortest_path_matrix instead, with every target's length from the
// start (all_searched). Lengths as shortest_path_matrix's. Settled
// targets have from_start_m and path_from_start, the others +inf and no
// path (not searched unless all_searched); between_m is n x n, +inf except
// between two of `nearest` and on the diagonal. The cost grows with `count`,
// not with the number of targets, where shortest_path_matrix's graph grows
// with the square of the map's reflex vertices, as long as `count` choice
// targets (or all of them) are reachable: a choice or required target the
// start cannot reach makes it search the start's whole piece of the C-space
// with a loop over every node per node (leave out targets in other pieces,
// ConfigurationSpace::piece_of). Pure and deterministic.
// `cache` as for shortest_path_matrix, which this calls for the whole graph.
PathMatrix shortest_paths_among_nearest(const ConfigurationSpace& cspace, const Point& start,
                                        const std::vector<Point>& targets, const NearestTargetsQuery& query,
                                        VisibilityCache* cache = nullptr);

}  // namespace pex::planning
