#include "planning/path_matrix.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "planning/test_maps.hpp"
#include "planning/visibility_graph.hpp"

namespace pex::planning {
namespace {

using testing::rectangle;
using testing::rectangle_hole;
using testing::typed_polygon;

// Uniform in [lo, hi) from the raw 64-bit output (the same on every standard
// library, unlike std::uniform_real_distribution).
double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// A 20 x 20 m room with a wall sticking in from the top (reflex vertices on
// the outer ring too) and `holes` random obstacles apart from each other:
// rectangles, regular polygons and L shapes.
mapping::TypedMultiPolygon random_map(std::mt19937_64& rng, int holes) {
  testing::RingSpec outer{{Point(0, 0), Point(20, 0), Point(20, 20), Point(12, 20), Point(12, 9), Point(11, 9),
                           Point(11, 20), Point(0, 20)},
                          {}};
  std::vector<mapping::Box> boxes{mapping::Box(Point(10.2, 8.2), Point(12.8, 21))};
  std::vector<testing::RingSpec> rings;
  for (int attempt = 0; attempt < 500 && static_cast<int>(rings.size()) < holes; ++attempt) {
    const double cx = uniform(rng, 2, 18), cy = uniform(rng, 2, 18), s = uniform(rng, 0.4, 1.8);
    const mapping::Box box(Point(cx - s - 0.8, cy - s - 0.8), Point(cx + s + 0.8, cy + s + 0.8));
    bool apart = box.min_corner().x() > 0 && box.min_corner().y() > 0 && box.max_corner().x() < 20 &&
                 box.max_corner().y() < 20;
    for (const auto& b : boxes) apart = apart && !boost::geometry::intersects(box, b);
    if (!apart) continue;
    boxes.push_back(box);
    const int kind = static_cast<int>(rng() % 3);
    if (kind == 0) {
      rings.push_back(rectangle_hole(cx - s, cy - s * 0.6, cx + s, cy + s * 0.6));
    } else if (kind == 1) {
      // Clockwise regular polygon, 5 to 9 corners, turned at random.
      const int k = 5 + static_cast<int>(rng() % 5);
      const double phase = uniform(rng, 0, 2 * M_PI);
      testing::RingSpec ring;
      for (int i = 0; i < k; ++i) {
        const double a = phase - 2 * M_PI * i / k;
        ring.points.emplace_back(cx + s * std::cos(a), cy + s * std::sin(a));
      }
      rings.push_back(ring);
    } else {
      // Clockwise L: a reflex corner on the obstacle, i.e. a convex one of the free space.
      rings.push_back(testing::RingSpec{{Point(cx - s, cy - s), Point(cx - s, cy + s), Point(cx, cy + s),
                                         Point(cx, cy), Point(cx + s, cy), Point(cx + s, cy - s)},
                                        {}});
    }
  }
  return {typed_polygon(outer, rings)};
}

// Random interior points of the C-space.
std::vector<Point> random_points(std::mt19937_64& rng, const ConfigurationSpace& cs, std::size_t count) {
  std::vector<Point> points;
  while (points.size() < count) {
    const Point p(uniform(rng, 0, 20), uniform(rng, 0, 20));
    if (cs.covers(p) && cs.distance_to_boundary(p) > 0.01) points.push_back(p);
  }
  return points;
}

// A random scene of trial `trial`: random_map with 4 + trial obstacles,
// robot radius 0.1-0.25 m, and `count` random interior points, the first of
// them the start.
struct RandomScene {
  ConfigurationSpace cs;
  Point start;
  std::vector<Point> targets;
};
void build_random_scene(std::mt19937_64& rng, int trial, std::size_t count, RandomScene& scene) {
  const auto map = random_map(rng, 4 + trial);
  CSpaceOptions o;
  o.robot_radius_m = 0.1 + 0.05 * (trial % 4);
  ASSERT_TRUE(scene.cs.build(map, o).ok);
  const auto points = random_points(rng, scene.cs, count);
  scene.start = points[0];
  scene.targets.assign(points.begin() + 1, points.end());
}

// A path from the start as the matrix gives it: at least two points, of
// `length_m`, every segment free.
// The oracle of the nearest: the choice targets the matrix reaches, by its
// lengths from the start (ties: the lower index first).
std::vector<int> choice_targets_by_length(const PathMatrix& m, const std::vector<char>& choice) {
  std::vector<int> by_length;
  for (std::size_t i = 0; i < m.size(); ++i)
    if (choice[i] && std::isfinite(m.from_start_m[i])) by_length.push_back(static_cast<int>(i));
  std::stable_sort(by_length.begin(), by_length.end(), [&](int a, int b) {
    return m.from_start_m[static_cast<std::size_t>(a)] < m.from_start_m[static_cast<std::size_t>(b)];
  });
  return by_length;
}

void expect_a_free_path(const std::vector<Point>& path, double length_m, const ConfigurationSpace& cs) {
  ASSERT_GE(path.size(), 2u);
  EXPECT_NEAR(polyline_length(path), length_m, 1e-9);
  for (std::size_t k = 1; k < path.size(); ++k) EXPECT_TRUE(cs.segment_free(path[k - 1], path[k]));
}

void expect_consistent(const PathMatrix& m, const ConfigurationSpace& cs, const Point& start) {
  const std::size_t n = m.size();
  ASSERT_EQ(m.between_m.size(), n * n);
  ASSERT_EQ(m.path_from_start.size(), n);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(m.between(i, i), 0.0);
    for (std::size_t j = 0; j < n; ++j) {
      EXPECT_EQ(m.between(i, j), m.between(j, i));  // exactly
      // Triangle inequality through every third target and through the start.
      for (std::size_t k = 0; k < n; ++k) {
        if (std::isfinite(m.between(i, k)) && std::isfinite(m.between(k, j))) {
          EXPECT_LE(m.between(i, j), m.between(i, k) + m.between(k, j) + 1e-9) << i << " " << k << " " << j;
        }
      }
      if (std::isfinite(m.from_start_m[i]) && std::isfinite(m.between(i, j))) {
        EXPECT_LE(m.from_start_m[j], m.from_start_m[i] + m.between(i, j) + 1e-9);
      }
      // Both reachable from the start: reachable from each other; one only: not.
      if (std::isfinite(m.from_start_m[i]) && std::isfinite(m.from_start_m[j])) {
        EXPECT_TRUE(std::isfinite(m.between(i, j)));
      }
      if (std::isfinite(m.from_start_m[i]) != std::isfinite(m.from_start_m[j])) {
        EXPECT_FALSE(std::isfinite(m.between(i, j)));
      }
    }
    if (!std::isfinite(m.from_start_m[i])) {
      EXPECT_TRUE(m.path_from_start[i].empty());
      continue;
    }
    const auto& path = m.path_from_start[i];
    ASSERT_NO_FATAL_FAILURE(expect_a_free_path(path, m.from_start_m[i], cs));
    EXPECT_EQ(path.front().x(), start.x());
    EXPECT_EQ(path.front().y(), start.y());
  }
}

TEST(PathMatrix, EmptyRoomIsStraightLines) {
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10))}, testing::disk(0.3)).ok);
  const std::vector<Point> targets{Point(8, 5), Point(2, 9), Point(5, 5)};
  const auto m = shortest_path_matrix(cs, Point(1, 1), targets);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m.reflex_nodes, 0);
  EXPECT_NEAR(m.from_start_m[0], std::hypot(7.0, 4.0), 1e-12);
  EXPECT_NEAR(m.between(0, 1), std::hypot(6.0, 4.0), 1e-12);
  EXPECT_NEAR(m.between(2, 1), std::hypot(3.0, 4.0), 1e-12);
  EXPECT_EQ(m.path_from_start[1].size(), 2u);
  expect_consistent(m, cs, Point(1, 1));
}

TEST(PathMatrix, AroundABlockBetweenTargetsToo) {
  // Block [4, 6] x [2, 8] in a 10 x 10 room, point robot: from (2, 5) to
  // (8, 5) over a corner, 2 * |(2, 3)| + 2 (+ millimetres for the node offset).
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build({typed_polygon(rectangle(0, 0, 10, 10), {rectangle_hole(4, 2, 6, 8)})}, testing::disk(0.0)).ok);
  const auto m = shortest_path_matrix(cs, Point(2, 5), {Point(8, 5), Point(2, 5.5)});
  const double around = 2.0 * std::hypot(2.0, 3.0) + 2.0;
  EXPECT_NEAR(m.from_start_m[0], around, 5e-3);
  EXPECT_EQ(m.path_from_start[0].size(), 4u);
  EXPECT_NEAR(m.from_start_m[1], 0.5, 1e-12);
  // From (2, 5.5) the top corners are nearer: |(2, 3)| + 2 + |(2, 2.5)|.
  EXPECT_NEAR(m.between(0, 1), std::hypot(2.0, 3.0) + 2.0 + std::hypot(2.0, 2.5), 5e-3);
  expect_consistent(m, cs, Point(2, 5));
}

TEST(PathMatrix, OtherPieceIsInfinite) {
  // Two rooms joined by a 0.4 m gap: a 0.5 m robot cannot pass.
  mapping::TypedMultiPolygon map{typed_polygon(testing::RingSpec{
      {Point(0, 0), Point(5, 0), Point(5, 2.3), Point(6, 2.3), Point(6, 0), Point(11, 0), Point(11, 5), Point(6, 5),
       Point(6, 2.7), Point(5, 2.7), Point(5, 5), Point(0, 5)},
      {}})};
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build(map, testing::disk(0.25)).ok);
  const auto m = shortest_path_matrix(cs, Point(1, 1), {Point(4, 4), Point(9, 4), Point(10, 1)});
  EXPECT_TRUE(std::isfinite(m.from_start_m[0]));
  EXPECT_FALSE(std::isfinite(m.from_start_m[1]));
  EXPECT_FALSE(std::isfinite(m.between(0, 1)));
  EXPECT_FALSE(std::isfinite(m.between(2, 0)));
  EXPECT_NEAR(m.between(1, 2), std::hypot(1.0, 3.0), 1e-12);
  expect_consistent(m, cs, Point(1, 1));

  const auto none = shortest_path_matrix(cs, Point(1, 1), {});
  EXPECT_EQ(none.size(), 0u);
  EXPECT_TRUE(none.between_m.empty());
}

// The matrix against shortest_paths (the full lazy visibility graph, no
// pruning) on random maps: from the start and between every pair of targets.
TEST(PathMatrix, AgreesWithShortestPathsOnRandomMaps) {
  std::mt19937_64 rng(20240611);
  std::int64_t pruned_edges = 0, all_edges = 0, compared = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const auto map = random_map(rng, 4 + trial);
    CSpaceOptions o;
    o.robot_radius_m = 0.1 + 0.05 * (trial % 4);
    o.points_per_circle = trial % 2 == 0 ? 16 : 8;
    ConfigurationSpace cs;
    ASSERT_TRUE(cs.build(map, o).ok);
    ASSERT_GT(cs.reflex_nodes().size(), 10u);
    const auto points = random_points(rng, cs, 13);
    const Point start = points[0];
    const std::vector<Point> targets(points.begin() + 1, points.end());
    const auto m = shortest_path_matrix(cs, start, targets);
    expect_consistent(m, cs, start);

    const auto sp = shortest_paths(cs, start, targets);
    for (std::size_t i = 0; i < targets.size(); ++i) {
      ASSERT_EQ(std::isfinite(sp.length_m[i]), std::isfinite(m.from_start_m[i]));
      if (std::isfinite(sp.length_m[i])) {
        EXPECT_NEAR(m.from_start_m[i], sp.length_m[i], 1e-6) << trial << " " << i;
      }
      const std::vector<Point> rest(targets.begin() + static_cast<std::ptrdiff_t>(i) + 1, targets.end());
      const auto from_i = shortest_paths(cs, targets[i], rest);
      for (std::size_t j = i + 1; j < targets.size(); ++j) {
        const double expected = from_i.length_m[j - i - 1];
        ASSERT_EQ(std::isfinite(expected), std::isfinite(m.between(i, j)));
        if (std::isfinite(expected)) {
          EXPECT_NEAR(m.between(i, j), expected, 1e-6) << trial << " " << i << " " << j;
        }
        ++compared;
      }
    }

    // Only from the start (the greedy strategy's search): the same row.
    const auto start_only = shortest_path_matrix(cs, start, targets, PathMatrixOptions{.between_targets = false});
    EXPECT_EQ(start_only.from_start_m, m.from_start_m);
    EXPECT_TRUE(start_only.between_m.empty());
    for (std::size_t i = 0; i < targets.size(); ++i)
      EXPECT_EQ(start_only.path_from_start[i].size(), m.path_from_start[i].size());

    // Without the pruning: the same lengths from many more edges.
    const auto full = shortest_path_matrix(cs, start, targets, PathMatrixOptions{.tangent_pruning = false});
    for (std::size_t i = 0; i < targets.size(); ++i) {
      EXPECT_EQ(std::isfinite(m.from_start_m[i]), std::isfinite(full.from_start_m[i]));
      if (std::isfinite(full.from_start_m[i])) {
        EXPECT_NEAR(m.from_start_m[i], full.from_start_m[i], 1e-6);
      }
      for (std::size_t j = 0; j < targets.size(); ++j) {
        if (std::isfinite(full.between(i, j))) {
          EXPECT_NEAR(m.between(i, j), full.between(i, j), 1e-6);
        }
      }
    }
    pruned_edges += m.graph_edges;
    all_edges += full.graph_edges;
  }
  EXPECT_EQ(compared, 12 * 66);
  // The tangent rule keeps well under half of the visible pairs.
  EXPECT_LT(pruned_edges * 3, all_edges) << pruned_edges << " of " << all_edges;
}

// The lazy search that stops at the cheapest target, against the matrix's
// row on random maps: what it settles has the matrix's lengths and paths,
// it finds the cheapest target and the required ones, and it tests fewer
// segments.
TEST(CheapestTarget, FindsTheMatrixCheapestAndTheRequiredTargets) {
  std::mt19937_64 rng(20261126);
  std::int64_t lazy_tests = 0, matrix_tests = 0;
  int stopped_early = 0;
  for (int trial = 0; trial < 12; ++trial) {
    RandomScene scene;
    ASSERT_NO_FATAL_FAILURE(build_random_scene(rng, trial, 25, scene));
    const ConfigurationSpace& cs = scene.cs;
    const Point& start = scene.start;
    const std::vector<Point>& targets = scene.targets;
    const auto m = shortest_path_matrix(cs, start, targets, PathMatrixOptions{.between_targets = false});
    // A cost that is not the length alone (at least the length, as the
    // contract asks); every third target no choice; one required, of the
    // median length (the required_target would have the search settle most of the
    // map, where it gives up for the graph's row: OnARaggedMap... below).
    auto cost = [&](std::size_t i, double length_m, const std::vector<Point>&) {
      return i % 3 == 2 ? std::numeric_limits<double>::infinity() : length_m + 0.5 * static_cast<double>(i % 4);
    };
    CheapestTargetQuery query;
    query.cost = cost;
    for (std::size_t i = 0; i < targets.size(); ++i) query.choice.push_back(i % 3 != 2);
    query.required.assign(targets.size(), 0);
    std::vector<std::size_t> reachable;
    for (std::size_t i = 0; i < targets.size(); ++i)
      if (std::isfinite(m.from_start_m[i])) reachable.push_back(i);
    ASSERT_FALSE(reachable.empty());
    std::sort(reachable.begin(), reachable.end(),
              [&](std::size_t a, std::size_t b) { return m.from_start_m[a] < m.from_start_m[b]; });
    const std::size_t required_target = reachable[reachable.size() / 2];
    query.required[required_target] = 1;
    const auto lazy = shortest_paths_to_cheapest(cs, start, targets, query);

    std::size_t cheapest = targets.size();
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < targets.size(); ++i) {
      if (!std::isfinite(m.from_start_m[i])) continue;
      const double c = cost(i, m.from_start_m[i], m.path_from_start[i]);
      if (c < least) least = c, cheapest = i;
    }
    ASSERT_LT(cheapest, targets.size());
    EXPECT_NEAR(lazy.from_start_m[cheapest], m.from_start_m[cheapest], 1e-9) << trial;
    EXPECT_NEAR(lazy.from_start_m[required_target], m.from_start_m[required_target], 1e-9) << trial;
    for (std::size_t i = 0; i < targets.size(); ++i) {
      if (!std::isfinite(lazy.from_start_m[i])) {
        // Not settled: not reachable, or no cheaper than the cheapest.
        EXPECT_TRUE(!std::isfinite(m.from_start_m[i]) || m.from_start_m[i] >= least - 1e-9) << trial << " " << i;
        EXPECT_TRUE(lazy.path_from_start[i].empty());
        continue;
      }
      EXPECT_NEAR(lazy.from_start_m[i], m.from_start_m[i], 1e-9) << trial << " " << i;
      ASSERT_NO_FATAL_FAILURE(expect_a_free_path(lazy.path_from_start[i], lazy.from_start_m[i], cs));
    }
    stopped_early += lazy.all_searched ? 0 : 1;
    lazy_tests += lazy.segment_tests;
    matrix_tests += m.segment_tests;
  }
  EXPECT_GT(stopped_early, 0);
  EXPECT_LT(lazy_tests, matrix_tests) << lazy_tests << " against " << matrix_tests;
}

TEST(CheapestTarget, WithoutAChoiceItSearchesEveryTarget) {
  std::mt19937_64 rng(5);
  const auto map = random_map(rng, 6);
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build(map, CSpaceOptions{}).ok);
  const auto points = random_points(rng, cs, 10);
  const std::vector<Point> targets(points.begin() + 1, points.end());
  CheapestTargetQuery query;
  query.cost = [](std::size_t, double, const std::vector<Point>&) { return std::numeric_limits<double>::infinity(); };
  const auto lazy = shortest_paths_to_cheapest(cs, points[0], targets, query);
  const auto m = shortest_path_matrix(cs, points[0], targets, PathMatrixOptions{.between_targets = false});
  EXPECT_TRUE(lazy.all_searched);
  for (std::size_t i = 0; i < targets.size(); ++i) EXPECT_NEAR(lazy.from_start_m[i], m.from_start_m[i], 1e-9);
}

// A ragged map: a wall across a 40 x 10 m room, open at both ends, and a
// row of small pillars on each side (190 reflex nodes). The only choice
// target is across the wall from the start: the search would settle most
// of the start's side on its way round, so it gives up for the graph's row
// (built through the cache), with every target's length and path. A target
// next to the start is found lazily, without the graph.
TEST(CheapestTarget, OnARaggedMapGivesUpForTheGraphsRow) {
  std::vector<testing::RingSpec> holes{rectangle_hole(2.0, 4.8, 38.0, 5.2)};
  for (double x = 3.0; x < 37.5; x += 1.5)
    for (const double y : {2.5, 7.5}) holes.push_back(rectangle_hole(x, y, x + 0.3, y + 0.3));
  const mapping::TypedMultiPolygon map{typed_polygon(rectangle(0, 0, 40, 10), holes)};
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build(map, testing::disk(0.1)).ok);
  const Point start(20.1, 1.5);
  const std::vector<Point> targets{Point(20.1, 8.5), Point(21.0, 1.5), Point(5.0, 9.0), Point(35.0, 1.0)};
  const auto m = shortest_path_matrix(cs, start, targets, PathMatrixOptions{.between_targets = false});
  for (std::size_t i = 0; i < targets.size(); ++i) ASSERT_TRUE(std::isfinite(m.from_start_m[i])) << i;

  // Target `only` the one choice, its cost its length.
  auto only_choice = [&](std::size_t only) {
    CheapestTargetQuery q;
    q.cost = [only](std::size_t i, double length_m, const std::vector<Point>&) {
      return i == only ? length_m : std::numeric_limits<double>::infinity();
    };
    q.choice.assign(targets.size(), 0);
    q.choice[only] = 1;
    return q;
  };
  VisibilityCache cache;
  const CheapestTargetQuery across = only_choice(0);
  const auto far = shortest_paths_to_cheapest(cs, start, targets, across, &cache);
  EXPECT_EQ(cache.counters().builds, 1);
  EXPECT_TRUE(far.all_searched);
  for (std::size_t i = 0; i < targets.size(); ++i) {
    EXPECT_NEAR(far.from_start_m[i], m.from_start_m[i], 1e-9) << i;
    ASSERT_NO_FATAL_FAILURE(expect_a_free_path(far.path_from_start[i], far.from_start_m[i], cs));
  }
  // The same without a cache: the same lengths.
  const auto far_uncached = shortest_paths_to_cheapest(cs, start, targets, across);
  EXPECT_EQ(far_uncached.from_start_m, far.from_start_m);

  const auto close = shortest_paths_to_cheapest(cs, start, targets, only_choice(1), &cache);
  EXPECT_EQ(cache.counters().builds, 1);
  EXPECT_FALSE(close.all_searched);
  EXPECT_NEAR(close.from_start_m[1], m.from_start_m[1], 1e-9);
  EXPECT_FALSE(std::isfinite(close.from_start_m[0]));
}

// The lazy search over the nearest targets against the whole matrix on
// random maps: it holds the `count` nearest choice targets (by the matrix's
// lengths), the lengths between them are the matrix's, and the required
// target has its path wherever it is; whether it searched lazily or, where
// that would cost more, took the whole matrix (both happen here).
TEST(NearestTargets, HoldTheMatrixLengthsAmongTheNearest) {
  std::mt19937_64 rng(20261127);
  int whole = 0, stopped = 0;
  for (int trial = 0; trial < 12; ++trial) {
    RandomScene scene;
    ASSERT_NO_FATAL_FAILURE(build_random_scene(rng, trial, 31, scene));
    const ConfigurationSpace& cs = scene.cs;
    const Point& start = scene.start;
    const std::vector<Point>& targets = scene.targets;
    const auto m = shortest_path_matrix(cs, start, targets);
    NearestTargetsQuery query;
    query.count = 4 + static_cast<std::size_t>(trial % 3) * 3;
    for (std::size_t i = 0; i < targets.size(); ++i) query.choice.push_back(i % 4 != 3);
    // The farthest reachable target is required.
    std::size_t farthest = 0;
    for (std::size_t i = 0; i < targets.size(); ++i)
      if (std::isfinite(m.from_start_m[i]) && m.from_start_m[i] > m.from_start_m[farthest]) farthest = i;
    query.required.assign(targets.size(), 0);
    query.required[farthest] = 1;
    const auto lazy = shortest_paths_among_nearest(cs, start, targets, query);

    // The nearest, by the matrix: choice targets sorted by length.
    const std::vector<int> by_length = choice_targets_by_length(m, query.choice);
    ASSERT_EQ(lazy.nearest.size(), std::min(query.count, by_length.size())) << trial;
    for (std::size_t k = 0; k < lazy.nearest.size(); ++k) {
      const auto i = static_cast<std::size_t>(lazy.nearest[k]);
      EXPECT_TRUE(query.choice[i]);
      // The k-th nearest (a tie may swap two of equal length).
      EXPECT_NEAR(m.from_start_m[i], m.from_start_m[static_cast<std::size_t>(by_length[k])], 1e-9) << trial << " " << k;
      EXPECT_NEAR(lazy.from_start_m[i], m.from_start_m[i], 1e-9);
      for (const int j : lazy.nearest)
        EXPECT_NEAR(lazy.between(i, static_cast<std::size_t>(j)), m.between(i, static_cast<std::size_t>(j)), 1e-9)
            << trial << " " << i << " " << j;
    }
    EXPECT_NEAR(lazy.from_start_m[farthest], m.from_start_m[farthest], 1e-9) << trial;
    // Settled targets have their path; between_m holds nothing else.
    for (std::size_t i = 0; i < targets.size(); ++i) {
      const bool among = std::find(lazy.nearest.begin(), lazy.nearest.end(), static_cast<int>(i)) != lazy.nearest.end();
      for (std::size_t j = 0; j < targets.size(); ++j) {
        const bool both = among && std::find(lazy.nearest.begin(), lazy.nearest.end(), static_cast<int>(j)) !=
                                       lazy.nearest.end();
        if (i != j && !both) {
          EXPECT_FALSE(std::isfinite(lazy.between(i, j)));
        }
      }
      if (!std::isfinite(lazy.from_start_m[i])) continue;
      EXPECT_NEAR(lazy.from_start_m[i], m.from_start_m[i], 1e-9);
      ASSERT_NO_FATAL_FAILURE(expect_a_free_path(lazy.path_from_start[i], lazy.from_start_m[i], cs));
    }
    // Stopped before it searched every target: the lazy search.
    (lazy.all_searched ? whole : stopped) += 1;
  }
  EXPECT_GT(whole, 0);
  EXPECT_GT(stopped, 0);
}

TEST(PathMatrix, BetweenTheNearestOnlyHoldsTheWholeMatrixLengthsThere) {
  std::mt19937_64 rng(20261128);
  for (int trial = 0; trial < 6; ++trial) {
    RandomScene scene;
    ASSERT_NO_FATAL_FAILURE(build_random_scene(rng, trial, 31, scene));
    const auto m = shortest_path_matrix(scene.cs, scene.start, scene.targets);
    const std::size_t n = scene.targets.size();
    PathMatrixOptions options;
    options.between_nearest = 3 + static_cast<std::size_t>(trial);
    for (std::size_t i = 0; i < n; ++i) options.between_choice.push_back(i % 3 != 1);
    const auto some = shortest_path_matrix(scene.cs, scene.start, scene.targets, options);

    std::vector<int> by_length = choice_targets_by_length(m, options.between_choice);
    if (by_length.size() > options.between_nearest) by_length.resize(options.between_nearest);
    ASSERT_GE(by_length.size(), 3u) << trial;
    EXPECT_EQ(some.nearest, by_length) << trial;
    EXPECT_EQ(some.from_start_m, m.from_start_m) << trial;  // the start's row: every target
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j) {
        const bool both = std::count(by_length.begin(), by_length.end(), static_cast<int>(i)) > 0 &&
                          std::count(by_length.begin(), by_length.end(), static_cast<int>(j)) > 0;
        if (i == j || both)
          EXPECT_EQ(some.between(i, j), m.between(i, j)) << trial << " " << i << " " << j;
        else
          EXPECT_FALSE(std::isfinite(some.between(i, j))) << trial << " " << i << " " << j;
      }
  }
}

TEST(PathMatrix, Deterministic) {
  std::mt19937_64 rng(7);
  const auto map = random_map(rng, 8);
  ConfigurationSpace cs;
  ASSERT_TRUE(cs.build(map, CSpaceOptions{}).ok);
  const auto points = random_points(rng, cs, 20);
  const std::vector<Point> targets(points.begin() + 1, points.end());
  const auto a = shortest_path_matrix(cs, points[0], targets);
  const auto b = shortest_path_matrix(cs, points[0], targets);
  EXPECT_EQ(a.between_m, b.between_m);
  EXPECT_EQ(a.from_start_m, b.from_start_m);
  for (std::size_t i = 0; i < targets.size(); ++i) {
    ASSERT_EQ(a.path_from_start[i].size(), b.path_from_start[i].size());
    for (std::size_t k = 0; k < a.path_from_start[i].size(); ++k)
      EXPECT_TRUE(boost::geometry::equals(a.path_from_start[i][k], b.path_from_start[i][k]));
  }
}

// A map that changes in places, as the explorer's maps do from one plan to
// the next: random_map's obstacles are placed in the same order whatever
// their number, so step by step one obstacle comes (8 steps) and goes again
// (7 steps). The points: half of the last step's that are still interior
// (kept exactly), and new ones.
struct ChangingScene {
  ConfigurationSpace cs;
  Point start;
  std::vector<Point> targets;
};
std::vector<ChangingScene> changing_scenes(std::uint64_t seed) {
  std::vector<ChangingScene> scenes(15);
  std::mt19937_64 rng(seed);
  std::vector<Point> last;
  for (int step = 0; step < 15; ++step) {
    std::mt19937_64 map_rng(seed);
    const int holes = step < 8 ? 3 + step : 17 - step;
    CSpaceOptions o;
    o.robot_radius_m = 0.2;
    ChangingScene& scene = scenes[static_cast<std::size_t>(step)];
    EXPECT_TRUE(scene.cs.build(random_map(map_rng, holes), o).ok);
    std::vector<Point> points = random_points(rng, scene.cs, 10);
    for (std::size_t k = 0; k < last.size(); k += 2)
      if (scene.cs.covers(last[k]) && scene.cs.distance_to_boundary(last[k]) > 0.01) points.push_back(last[k]);
    scene.start = points[0];
    scene.targets.assign(points.begin() + 1, points.end());
    last = points;
  }
  return scenes;
}

// The graph through the cache is the graph built afresh, edge for edge,
// while obstacles come and go (pairs that saw each other are cut, pairs cut
// see each other again) and nodes are kept, moved and new.
TEST(VisibilityCache, GraphIsTheOneBuiltAfreshWhileTheMapChanges) {
  for (const std::uint64_t seed : {11u, 12u, 13u}) {
    VisibilityCache cache;
    for (const ChangingScene& scene : changing_scenes(seed)) {
      std::vector<Point> nodes = scene.cs.reflex_nodes();
      const auto r = static_cast<std::uint32_t>(nodes.size());
      nodes.push_back(scene.start);
      nodes.insert(nodes.end(), scene.targets.begin(), scene.targets.end());
      const EdgeList fresh = pruned_graph_edges(scene.cs, nodes, r, true);
      const EdgeList cached = pruned_graph_edges(scene.cs, nodes, r, true, &cache);
      ASSERT_FALSE(fresh.a.empty());
      EXPECT_EQ(cached.a, fresh.a) << "seed " << seed;
      EXPECT_EQ(cached.b, fresh.b) << "seed " << seed;
      EXPECT_EQ(cached.length, fresh.length) << "seed " << seed;
    }
    // Every way through the cache was taken.
    const auto& c = cache.counters();
    EXPECT_EQ(c.builds, 15);
    EXPECT_GT(c.kept, 0);
    EXPECT_GT(c.retested, 0);
    EXPECT_GT(c.new_pairs, 0);
  }
}

// A map moved as a whole (SLAM corrected the pose it was built from) shares
// no boundary edge with the last: the graph is built afresh, and the one
// after it, on the same map, answers every test from it.
TEST(VisibilityCache, AMapMovedAsAWholeIsBuiltAfresh) {
  VisibilityCache cache;
  std::vector<EdgeList> fresh;
  for (const double shift_m : {0.0, 0.37, 0.37}) {
    std::mt19937_64 map_rng(5);
    auto map = random_map(map_rng, 6);
    boost::geometry::strategy::transform::translate_transformer<double, 2, 2> move(shift_m, 0.0);
    mapping::TypedMultiPolygon moved = map;
    boost::geometry::transform(map[0].geometry, moved[0].geometry, move);
    ConfigurationSpace cs;
    ASSERT_TRUE(cs.build(moved, CSpaceOptions{}).ok);
    std::vector<Point> nodes = cs.reflex_nodes();
    const auto r = static_cast<std::uint32_t>(nodes.size());
    nodes.push_back(Point(1 + shift_m, 1));
    fresh.push_back(pruned_graph_edges(cs, nodes, r, true));
    const EdgeList cached = pruned_graph_edges(cs, nodes, r, true, &cache);
    EXPECT_EQ(cached.a, fresh.back().a);
    EXPECT_EQ(cached.b, fresh.back().b);
    EXPECT_EQ(cached.length, fresh.back().length);
  }
  ASSERT_FALSE(fresh[1].a.empty());
  const auto& c = cache.counters();
  EXPECT_EQ(c.rebuilt, 2);  // the first graph (nothing before it) and the moved one
  EXPECT_EQ(c.retested, 0);
  // The third graph: every pair from the second.
  EXPECT_EQ(c.kept, c.new_pairs / 2);
}

// What the planner asks of the matrix is the same with the cache.
TEST(VisibilityCache, ChangesNoLengthNorPathOfTheMatrixOrTheNearest) {
  VisibilityCache whole_cache, nearest_cache;
  for (const ChangingScene& scene : changing_scenes(21)) {
    const PathMatrix fresh = shortest_path_matrix(scene.cs, scene.start, scene.targets);
    const PathMatrix cached = shortest_path_matrix(scene.cs, scene.start, scene.targets, {}, &whole_cache);
    EXPECT_EQ(cached.from_start_m, fresh.from_start_m);
    ASSERT_EQ(cached.path_from_start.size(), fresh.path_from_start.size());
    for (std::size_t t = 0; t < fresh.path_from_start.size(); ++t) {
      const auto &a = cached.path_from_start[t], &b = fresh.path_from_start[t];
      ASSERT_EQ(a.size(), b.size());
      for (std::size_t k = 0; k < a.size(); ++k) EXPECT_TRUE(a[k].x() == b[k].x() && a[k].y() == b[k].y());
    }
    EXPECT_EQ(cached.between_m, fresh.between_m);
    EXPECT_EQ(cached.graph_edges, fresh.graph_edges);
    NearestTargetsQuery query;
    query.count = 4;
    const PathMatrix nearest = shortest_paths_among_nearest(scene.cs, scene.start, scene.targets, query);
    const PathMatrix nearest_cached =
        shortest_paths_among_nearest(scene.cs, scene.start, scene.targets, query, &nearest_cache);
    EXPECT_EQ(nearest_cached.nearest, nearest.nearest);
    EXPECT_EQ(nearest_cached.from_start_m, nearest.from_start_m);
    EXPECT_EQ(nearest_cached.between_m, nearest.between_m);
  }
  EXPECT_GT(whole_cache.counters().kept, 0);
}

}  // namespace
}  // namespace pex::planning
