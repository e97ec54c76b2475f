#pragma once
// Shortest paths in the configuration space: Dijkstra over the visibility
// graph whose nodes are the start, the C-space's reflex vertices and the
// targets, with an edge wherever the straight segment stays inside the
// C-space. In a polygonal domain every shortest path bends only at reflex
// vertices, so this yields the exact shortest polylines (up to the interior
// offset of the nodes).
//
// The graph is built lazily: edges are tested only from settled nodes and
// only when they would improve a tentative distance, and the search stops
// once every target is settled.
#include <cstdint>
#include <limits>
#include <vector>

#include "planning/cspace.hpp"

namespace pex::planning {

struct ShortestPaths {
  // Per target: path length (+inf if unreachable) and the polyline from the
  // start to the target (empty if unreachable).
  std::vector<double> length_m;
  std::vector<std::vector<Point>> path;
  std::int64_t nodes = 0;            // start + reflex vertices + targets
  std::int64_t segment_tests = 0;    // visibility tests made
};

// `start` and every target should lie in the C-space's interior (see
// ConfigurationSpace::nearest_interior_point); a target is reachable only if
// it lies in the same connected piece of the C-space as the start. Targets
// are path ends, never intermediate nodes. Deterministic: ties go to the
// lower node index.
ShortestPaths shortest_paths(const ConfigurationSpace& cspace, const Point& start,
                             const std::vector<Point>& targets);

}  // namespace pex::planning
