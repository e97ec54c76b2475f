#include "planning/exploration_planner.hpp"

#include "planning/path_matrix.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <utility>

#include <boost/geometry/index/rtree.hpp>

namespace pex::planning {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

namespace {

// The map's obstacle edges, for line-of-sight tests.
class ObstacleEdges {
 public:
  explicit ObstacleEdges(const TypedMultiPolygon& map) {
    std::vector<Value> values;
    mapping::for_each_edge(map, [&](const Point& a, const Point& b, EdgeType t) {
      if (t == EdgeType::kObstacle) values.emplace_back(mapping::Segment(a, b), values.size());
    });
    tree_ = Tree(values.begin(), values.end());  // packed: built once, queried a few hundred times
  }
  // True if an obstacle edge shares a point with the segment a-b.
  bool blocks(const Point& a, const Point& b) const {
    for (auto it = tree_.qbegin(bgi::intersects(mapping::Segment(a, b))); it != tree_.qend(); ++it)
      if (segments_intersect(a, b, it->first.first, it->first.second)) return true;
    return false;
  }
  // The frontier point f is in view from `from`: no obstacle edge on the way,
  // which stops 1 cm short of f (f lies on the map's boundary, often at the
  // end of an obstacle edge, which is not a wall in the way).
  bool in_view(const Point& from, const Point& f) const {
    const double d = distance(from, f);
    if (d <= 0.01) return true;
    const Point short_of_f(f.x() + (from.x() - f.x()) * 0.01 / d, f.y() + (from.y() - f.y()) * 0.01 / d);
    return !blocks(from, short_of_f);
  }
  // The obstacle edges whose boxes meet `window`, as a.x a.y b.x b.y each,
  // sorted: what a line-of-sight test inside the window can meet.
  std::vector<double> near(const mapping::Box& window) const {
    std::vector<std::array<double, 4>> found;
    for (auto it = tree_.qbegin(bgi::intersects(window)); it != tree_.qend(); ++it)
      found.push_back({it->first.first.x(), it->first.first.y(), it->first.second.x(), it->first.second.y()});
    std::sort(found.begin(), found.end());
    std::vector<double> flat;
    flat.reserve(4 * found.size());
    for (const auto& e : found) flat.insert(flat.end(), e.begin(), e.end());
    return flat;
  }
  // True if no obstacle edge comes within `clearance` of the segment a-b:
  // a disk of that radius moves along it touching no wall.
  bool clear_of(const Point& a, const Point& b, double clearance) const {
    const mapping::Box box(Point(std::min(a.x(), b.x()) - clearance, std::min(a.y(), b.y()) - clearance),
                           Point(std::max(a.x(), b.x()) + clearance, std::max(a.y(), b.y()) + clearance));
    for (auto it = tree_.qbegin(bgi::intersects(box)); it != tree_.qend(); ++it)
      if (segment_distance(a, b, it->first.first, it->first.second) < clearance) return false;
    return true;
  }

 private:
  using Value = std::pair<mapping::Segment, std::size_t>;
  using Tree = bgi::rtree<Value, bgi::rstar<16>>;
  Tree tree_;
};

// The nearest point of `piece` (a C-space polygon) within `range_m` of the
// frontier point `f` from which f is in view, moved into the interior.
// Points along the piece's boundary every kStep are tried nearest first.
// With `cache`, the tries of an earlier plan whose edges near f were the same
// are taken from it (ApproachCache): the answer is the same either way.
std::optional<Point> approach_point(const ConfigurationSpace& cspace, int piece_index, const Point& f,
                                    double range_m, const ObstacleEdges& obstacles, ApproachCache* cache) {
  constexpr double kStep = 0.25;       // m between tried points along the boundary
  constexpr std::size_t kTries = 48;   // line-of-sight tests at most
  // What a try depends on lies within range_m of f plus the few millimetres
  // nearest_interior_point moves it; a metre more is ample.
  const double window_m = range_m + 1.0;
  std::vector<std::uint32_t> window_edges = cspace.edges_near(f, window_m);
  std::sort(window_edges.begin(), window_edges.end());  // by index: ties resolve as they did
  ApproachCache::Memo* memo = nullptr;
  if (cache) {
    std::vector<double> edges;
    edges.reserve(5 * window_edges.size());
    for (const std::uint32_t index : window_edges) {
      const ConfigurationSpace::Edge& e = cspace.edges()[index];
      edges.insert(edges.end(), {e.a.x(), e.a.y(), e.b.x(), e.b.y(),
                                 e.polygon == static_cast<std::uint32_t>(piece_index) ? 1.0 : 0.0});
    }
    std::vector<double> walls =
        obstacles.near(mapping::Box(Point(f.x() - window_m, f.y() - window_m), Point(f.x() + window_m, f.y() + window_m)));
    const CSpaceOptions& o = cspace.options();
    memo = &cache->memo(f, o.robot_radius_m + o.clearance_margin_m, range_m);
    const bool same = memo->filled && memo->cspace_edges == edges && memo->obstacle_edges == walls;
    cache->count(same);
    if (!same) {
      memo->cspace_edges = std::move(edges);
      memo->obstacle_edges = std::move(walls);
      memo->filled = true;
      memo->tried = 0;
      memo->seen_from.clear();
    }
    for (const Point& inside : memo->seen_from)
      if (cspace.piece_of(inside) == piece_index) return inside;
  }
  std::vector<std::pair<double, Point>> near;
  for (const std::uint32_t index : window_edges) {
    const ConfigurationSpace::Edge& e = cspace.edges()[index];
    if (e.polygon != static_cast<std::uint32_t>(piece_index)) continue;
    const Point& a = e.a;
    const Point& b = e.b;
    if (distance(f, closest_point_on_segment(f, a, b)) > range_m) continue;
    const double length = distance(a, b);
    const int n = std::max(1, static_cast<int>(std::ceil(length / kStep)));
    for (int k = 0; k < n; ++k) {
      const double t = (k + 0.5) / n;
      const Point q(a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y()));
      const double d = distance(f, q);
      if (d <= range_m) near.emplace_back(d, q);
    }
  }
  // Ties by coordinates: the answer does not depend on the edges' order.
  // Only the nearest kTries are ever tried (a ragged wall within range_m
  // gives thousands of points): those are put in order, not the rest.
  const std::size_t tries = std::min(near.size(), kTries);
  std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(tries), near.end(),
                    [](const auto& a, const auto& b) {
                      if (a.first != b.first) return a.first < b.first;
                      if (a.second.x() != b.second.x()) return a.second.x() < b.second.x();
                      return a.second.y() < b.second.y();
                    });
  for (std::size_t i = memo ? memo->tried : 0; i < tries; ++i) {
    const auto inside = cspace.nearest_interior_point(near[i].second, 0.05);
    if (memo) memo->tried = i + 1;
    // The line of sight first: most tries fail it, and piece_of's ray
    // crosses the whole map.
    if (!inside || !obstacles.in_view(*inside, f)) continue;
    if (memo) memo->seen_from.push_back(*inside);
    if (cspace.piece_of(*inside) == piece_index) return inside;
  }
  return std::nullopt;
}

// Points of the arc [from_m, to_m] of a chain other than its middle, nearest
// the middle first, kStep apart, at most kPoints (the arc's ends among them
// when the arc is short): where a candidate whose middle no place sees is
// looked at from instead (plan_exploration).
std::vector<Point> off_middle_points(const std::vector<Point>& chain, double from_m, double to_m) {
  constexpr double kStep = 0.25;
  constexpr std::size_t kPoints = 8;
  const double middle = 0.5 * (from_m + to_m), half = 0.5 * (to_m - from_m);
  std::vector<Point> out;
  for (int k = 1; half > 0.0 && out.size() < kPoints; ++k) {
    const double s = std::min(k * kStep, half);  // the last step ends at the arc's ends
    out.push_back(point_at_arc_length(chain, middle - s));
    if (out.size() < kPoints) out.push_back(point_at_arc_length(chain, middle + s));
    if (s >= half) break;
  }
  return out;
}

// Whether the robot's disk reaches `reach_m` past the frontier somewhere
// along [from_m, to_m] of `chain` (PlannerOptions::reach_past_frontier_m).
// The arc is sampled every kStep. At a sample f the disk (centre c within
// radius - reach_m of f, so it covers reach_m beyond f) must keep the
// radius from every obstacle edge, and get there straight from the C-space:
//  - from the C-space point nearest f (the C-space keeps the radius plus the
//    margin from every map edge, the frontier's too), moving towards f;
//  - or square in front of f (c on the free side's normal), from the
//    C-space point nearest c within way_m: a gap between the margin and
//    the radius (0.6 m for a 0.54 m robot) has no C-space of its own, and
//    the robot still looks into it from its mouth.
// Why that is enough: the centre of a robot that first touches unknown
// space behind some frontier has come from the C-space through points
// closer than radius plus margin to frontier edges only, starting at the
// C-space's boundary, within radius plus margin of that frontier; so while
// floor the robot could sweep is unknown, some frontier passes this test
// (up to the sampling step and a way in that is not straight).
bool disk_reaches_past(const ConfigurationSpace& cspace, const ObstacleEdges& obstacles, const FrontierChain& chain,
                       double from_m, double to_m, double reach_m, double way_m) {
  constexpr double kStep = 0.05;  // m between samples along the frontier
  const CSpaceOptions& o = cspace.options();
  const double radius = o.robot_radius_m;
  // The C-space lies radius + margin from the frontier, less RDP's epsilon;
  // a sample may be half a step from the nearest point of the frontier.
  const double search_m = radius + o.clearance_margin_m + o.simplify_epsilon_m + kStep;
  const double centre_m = radius - reach_m;  // from f, where the centre must get
  if (!(centre_m > 0.0)) return true;
  // f on edge a-b of the chain; free space is on the edge's left.
  auto reaches_at = [&](const Point& f, const Point& a, const Point& b) {
    if (const auto c = cspace.nearest_interior_point(f, search_m)) {
      const double d = distance(*c, f);
      if (d <= centre_m) return true;
      const Point end(f.x() + (c->x() - f.x()) * centre_m / d, f.y() + (c->y() - f.y()) * centre_m / d);
      if (obstacles.clear_of(*c, end, radius)) return true;
    }
    const Point n = left_normal(a, b);
    if (n.x() == 0.0 && n.y() == 0.0) return false;  // a == b: no free side
    const Point front(f.x() + n.x() * centre_m, f.y() + n.y() * centre_m);
    if (!obstacles.clear_of(front, front, radius)) return false;
    const auto c = cspace.nearest_interior_point(front, way_m);
    return c && obstacles.clear_of(*c, front, radius);
  };
  // Every kStep from from_m, and to_m itself; the samples are in arc order,
  // so the edge each lies on is found walking forward.
  if (chain.points.size() < 2) return false;
  const int steps = std::max(1, static_cast<int>(std::ceil((to_m - from_m) / kStep)));
  std::size_t i = 1;  // the sample lies on edge points[i - 1] - points[i]
  double at = 0.0;    // arc length at points[i - 1]
  double length = distance(chain.points[0], chain.points[1]);  // of that edge
  for (int k = 0; k <= steps; ++k) {
    const double s = k == steps ? to_m : from_m + k * kStep;
    while (i + 1 < chain.points.size() && s > at + length) {
      at += length;
      ++i;
      length = distance(chain.points[i - 1], chain.points[i]);
    }
    const Point& a = chain.points[i - 1];
    const Point& b = chain.points[i];
    const double t = length > 0.0 ? std::clamp((s - at) / length, 0.0, 1.0) : 0.0;
    if (reaches_at(Point(a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y())), a, b)) return true;
  }
  return false;
}

// True if the segment a-b crosses or touches an edge of `map`, of either
// type: it leaves the free space the map knows. Looks at every edge: for the
// rare question only (a start moved off a sliver).
bool crosses_an_edge(const TypedMultiPolygon& map, const Point& a, const Point& b) {
  bool crosses = false;
  mapping::for_each_edge(map, [&](const Point& p, const Point& q, EdgeType) {
    crosses = crosses || segments_intersect(a, b, p, q);
  });
  return crosses;
}

// The C-space of `map` and the robot's node in it, with their statistics in
// `plan`; nullopt (and plan.error) when there is none.
struct Setup {
  ConfigurationSpace cspace;
  Point robot_point;
  Point start;
};
std::optional<Setup> set_up(const TypedMultiPolygon& map, const Pose2& robot, const PlannerOptions& options,
                            PlanCache* cache, const DrivenWay* way, Plan& plan) {
  if (!std::isfinite(robot.x_m) || !std::isfinite(robot.y_m) || !std::isfinite(robot.theta_rad)) {
    plan.error = "robot pose is not finite";
    return std::nullopt;
  }
  Setup s;
  auto build = [&](const DrivenWay* along) {
    const auto built = s.cspace.build(map, options.cspace, cache ? &cache->offsets : nullptr, along);
    if (!built.ok) plan.error = built.error;
    return built.ok;
  };
  if (!build(way)) return std::nullopt;
  s.robot_point = Point(robot.x_m, robot.y_m);
  auto start = s.cspace.nearest_interior_point(s.robot_point, options.start_snap_distance_m);
  if (!start && way && !way->points.empty() && !way->keep_where_the_robot_stands) {
    // Farther outside than a start may snap, but on its trail (a way in,
    // then SLAM moved the pose: campus, 0.54 m out, and the mission FAILED
    // on five such plans): the C-space again with the trail's corridor
    // about the robot, its way back in. Only then: where the robot is near
    // the C-space the start snaps to it straight, not back along the trail.
    DrivenWay standing = *way;
    standing.keep_where_the_robot_stands = true;
    if (!build(&standing)) return std::nullopt;
    start = s.cspace.nearest_interior_point(s.robot_point, options.start_snap_distance_m);
  }
  plan.stats.cspace_vertices = static_cast<int>(mapping::vertex_count(s.cspace.polygons()));
  plan.stats.reflex_nodes = static_cast<int>(s.cspace.reflex_nodes().size());
  if (!start) {
    plan.robot_outside_cspace = true;
    plan.error = "the robot is not within " + std::to_string(options.start_snap_distance_m) +
                 " m of the configuration space";
    return std::nullopt;
  }
  s.start = *start;
  if (options.start_sliver_area_m2 > 0.0) {
    const int piece = s.cspace.piece_of(s.start);
    if (piece >= 0 && bg::area(s.cspace.polygons()[static_cast<std::size_t>(piece)].geometry) <
                          options.start_sliver_area_m2) {
      // The nearest point of another piece, if that piece is no sliver and
      // nothing of the map stands between it and the robot.
      const auto other = s.cspace.nearest_interior_point(s.robot_point, options.start_snap_distance_m, piece);
      const int other_piece = other ? s.cspace.piece_of(*other) : -1;
      if (other_piece >= 0 &&
          bg::area(s.cspace.polygons()[static_cast<std::size_t>(other_piece)].geometry) >=
              options.start_sliver_area_m2 &&
          !crosses_an_edge(map, s.robot_point, *other)) {
        s.start = *other;
        ++plan.stats.start_sliver_skipped;
      }
    }
  }
  return s;
}

}  // namespace

void ApproachCache::begin_plan() {
  ++plan_;
  // A frontier point asked about in none of the last few plans is gone (the
  // map moved on) or rare: its memo is not worth its memory.
  constexpr std::int64_t kPlansKept = 4;
  std::erase_if(memos_, [&](const auto& entry) { return entry.second.last_plan < plan_ - kPlansKept; });
}

ApproachCache::Memo& ApproachCache::memo(const Point& f, double clearance_m, double range_m) {
  Memo& m = memos_[{f.x(), f.y(), clearance_m, range_m}];
  m.last_plan = plan_;
  return m;
}

VisibilityCache& PlanCache::visibility(const CSpaceOptions& cspace) {
  const double clearance_m = cspace.robot_radius_m + cspace.clearance_margin_m;
  ++uses_;
  for (Slot& slot : slots_)
    if (slot.clearance_m == clearance_m) {
      slot.last_use = uses_;
      return *slot.cache;
    }
  constexpr std::size_t kClearances = 3;
  if (slots_.size() >= kClearances) {
    const auto oldest = std::min_element(slots_.begin(), slots_.end(),
                                         [](const Slot& a, const Slot& b) { return a.last_use < b.last_use; });
    dropped_ += oldest->cache->counters();
    slots_.erase(oldest);
  }
  slots_.push_back({clearance_m, uses_, std::make_unique<VisibilityCache>()});
  return *slots_.back().cache;
}

VisibilityCache::Counters PlanCache::visibility_counters() const {
  VisibilityCache::Counters sum = dropped_;
  for (const Slot& slot : slots_) sum += slot.cache->counters();
  return sum;
}

const char* to_string(GoalStrategy strategy) {
  switch (strategy) {
    case GoalStrategy::kGreedy: return "greedy";
    case GoalStrategy::kTour: return "tour";
  }
  return "?";
}

std::optional<GoalStrategy> parse_goal_strategy(std::string_view name) {
  if (name == "greedy") return GoalStrategy::kGreedy;
  if (name == "tour") return GoalStrategy::kTour;
  return std::nullopt;
}

int Plan::reachable_count() const {
  int n = 0;
  for (const auto& c : candidates) n += (c.reachable && !c.blacklisted) ? 1 : 0;
  return n;
}

bool margin_may_block(const Plan& plan) {
  if (plan.robot_outside_cspace || plan.stats.candidates_not_in_cspace > 0) return true;
  return std::any_of(plan.candidates.begin(), plan.candidates.end(),
                     [](const GoalCandidate& c) { return !c.blacklisted && !c.reachable; });
}

double GoalFocus::distance_to(const GoalCandidate& c) const {
  return std::min(distance(c.position, goal), distance(c.frontier_point, frontier));
}

namespace {

// Step 4 of plan_exploration for the tour: the tour's stops and their first
// legs (each candidate's cost from the robot), the shortest open tour through
// them, and its first stop as the goal unless the first-leg bound says the
// nearest. `matrix` is the plan's; its between_m is overwritten.
void choose_by_tour(PathMatrix& matrix, const TourOptions& options, Plan& plan) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const std::size_t n = plan.candidates.size();
  std::vector<double> first_leg(n, kInf);
  for (std::size_t i = 0; i < n; ++i)
    if (plan.candidates[i].reachable && !plan.candidates[i].blacklisted) first_leg[i] = plan.candidates[i].cost;
  if (options.horizon_candidates > 0) {
    // Only the nearest horizon_candidates by path length: the candidates the matrix holds.
    std::vector<double> nearest_only(n, kInf);
    for (const int i : matrix.nearest) nearest_only[static_cast<std::size_t>(i)] = first_leg[static_cast<std::size_t>(i)];
    first_leg = std::move(nearest_only);
  }
  if (options.one_per_chain) {
    // The cheapest candidate of each chain stands for it (ties: the lower index).
    std::map<int, std::size_t> cheapest_of_chain;
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(first_leg[i])) continue;
      const auto [it, fresh] = cheapest_of_chain.try_emplace(plan.candidates[i].chain, i);
      if (!fresh && first_leg[i] < first_leg[it->second]) it->second = i;
    }
    for (std::size_t i = 0; i < n; ++i)
      if (std::isfinite(first_leg[i]) && cheapest_of_chain[plan.candidates[i].chain] != i) first_leg[i] = kInf;
  }
  std::vector<double>& between = matrix.between_m;
  for (std::size_t i = 0; i < n; ++i)  // keep the matrix finite where the solver needs it (the stops' rows)
    for (std::size_t j = 0; j < n; ++j)
      if (!std::isfinite(first_leg[i]) || !std::isfinite(first_leg[j])) between[i * n + j] = 0.0;
  const OpenTour tour = solve_open_tour(first_leg, between, options);
  plan.tour = tour.order;
  if (!tour.order.empty()) plan.best = tour.order.front();
  if (plan.best >= 0 && options.max_first_leg_ratio > 0.0) {
    const auto nearest =
        static_cast<std::size_t>(std::min_element(first_leg.begin(), first_leg.end()) - first_leg.begin());
    const auto first = static_cast<std::size_t>(plan.best);
    if (first_leg[first] > options.max_first_leg_ratio * first_leg[nearest] + options.first_leg_slack_m)
      plan.best = static_cast<int>(nearest);
  }
}

// Whether `piece` (an index into cspace.polygons()) is smaller than the
// C-space's largest piece (PlanStats::robot_in_a_lesser_piece).
bool is_a_lesser_piece(const ConfigurationSpace& cspace, int piece) {
  const auto& pieces = cspace.polygons();
  const double area_m2 = bg::area(pieces[static_cast<std::size_t>(piece)].geometry);
  return std::any_of(pieces.begin(), pieces.end(),
                     [&](const auto& other) { return bg::area(other.geometry) > area_m2; });
}

// The index of the cheapest candidate that may be a goal (reachable, not
// blacklisted) and that `also` accepts; the first of equal costs; -1: none.
template <class Accept>
int cheapest_goal(const Plan& plan, Accept also) {
  int best = -1;
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    const auto& c = plan.candidates[i];
    if (!c.reachable || c.blacklisted || !also(c)) continue;
    if (best < 0 || c.cost < plan.candidates[static_cast<std::size_t>(best)].cost) best = static_cast<int>(i);
  }
  return best;
}

// Where to look at a gap about the robot's width from: on the narrower
// disk's shortest path through it, the last point still in the robot's piece
// of the plan's C-space (the path leaves that piece for good at the gap; the
// bends before it, round the narrower disk's corners, come back into it),
// moved into the piece's interior; where that point has no interior point of
// the piece near it (a sliver of the piece's edge), the one before it, up to
// a metre back. nullopt if there is none.
std::optional<Point> gap_mouth(const ConfigurationSpace& cspace, int own_piece, const std::vector<Point>& path) {
  constexpr double kStepM = 0.05;
  constexpr int kTries = 20;
  std::vector<Point> in_piece;  // the path's samples in the robot's piece, in order
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    const Point& a = path[k];
    const Point& b = path[k + 1];
    const int n = std::max(1, static_cast<int>(std::ceil(distance(a, b) / kStepM)));
    for (int j = 0; j <= n; ++j) {
      const double t = static_cast<double>(j) / n;
      const Point q(a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y()));
      if (cspace.piece_of(q) == own_piece) in_piece.push_back(q);
    }
  }
  for (int tried = 0; tried < kTries && !in_piece.empty(); ++tried, in_piece.pop_back()) {
    const auto inside = cspace.nearest_interior_point(in_piece.back(), kStepM);
    if (inside && cspace.piece_of(*inside) == own_piece) return inside;
  }
  return std::nullopt;
}

// Step 5 of plan_exploration (PlannerOptions::narrow_gap_tolerance_m). The
// candidates without a path (in another piece of the C-space than the
// robot's start, not an approach point) are looked at in the C-space of a
// disk narrow_gap_tolerance_m smaller, without margin:
//  - those still apart from the robot there are behind gaps narrower than
//    the robot: out of the candidates, into Plan::behind_narrow_gap_points
//    (only when the plan has no goal);
//  - those it joins to the robot are behind a gap about the robot's width,
//    which may be a door the map narrowed: returned with the mouth of that
//    gap (gap_mouth), for plan_exploration to make them approach points
//    there (when the plan has no goal, or for the followed goal).
// Nothing while the robot's piece of that C-space is not its largest.
// `pieces` holds each candidate's piece.
std::vector<std::pair<std::size_t, Point>> settle_behind_narrow_gaps(
    const ConfigurationSpace& plan_cspace, const TypedMultiPolygon& drivable, const Point& start,
    const PlannerOptions& options, const GoalFocus* focus, const DrivenWay* way,
    const std::vector<int>& pieces, int own_piece, PlanCache* cache, Plan& plan) {
  std::vector<std::size_t> apart;
  bool focus_apart = false;
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    const auto& c = plan.candidates[i];
    if (!c.reachable && !c.blacklisted && !c.approach && pieces[i] >= 0 && pieces[i] != own_piece) {
      apart.push_back(i);
      focus_apart = focus_apart || (focus && focus->matches(c));
    }
  }
  const bool no_goal = plan.best < 0;
  if (apart.empty() || (!no_goal && !focus_apart)) return {};
  CSpaceOptions narrower = options.cspace;
  narrower.robot_radius_m -= options.narrow_gap_tolerance_m;
  narrower.clearance_margin_m = 0.0;
  ConfigurationSpace cspace;
  // The offset tiles and the path graph's segment tests are kept for this
  // clearance too: the endgame plans with the margin, without it and with
  // this one by turns, on maps that change little (OffsetTileCache keeps what
  // the last calls used, PlanCache a VisibilityCache per clearance). Without
  // them each such plan built this C-space's whole graph afresh: 20 ms of a
  // 50 ms tight plan on campus's 1900 reflex nodes (docs/exploration.md,
  // "Planning time").
  if (!cspace.build(drivable, narrower, cache ? &cache->offsets : nullptr, way).ok) return {};
  const auto robot_at = cspace.nearest_interior_point(start, options.start_snap_distance_m);
  if (!robot_at) return {};
  const int robot_piece = cspace.piece_of(*robot_at);
  if (robot_piece < 0) return {};
  // A robot in a lesser part of the map is shut in a nook more likely than
  // the rest of the map is shut off from it (a gap it came through, closed
  // by a newer map and not on its trail): the mission backs out first.
  if (is_a_lesser_piece(cspace, robot_piece)) return {};
  std::vector<char> behind(plan.candidates.size(), 0);
  std::vector<std::size_t> within;  // joined to the robot by the narrower disk
  std::vector<Point> within_at;
  for (const std::size_t i : apart) {
    // The narrower disk's C-space holds the robot's: a point of it is near.
    const auto at = cspace.nearest_interior_point(plan.candidates[i].position, options.candidate_snap_distance_m);
    if (!at) continue;
    if (cspace.piece_of(*at) != robot_piece) {
      behind[i] = no_goal;
    } else if (no_goal || focus->matches(plan.candidates[i])) {
      within.push_back(i);
      within_at.push_back(*at);
    }
  }
  std::vector<std::pair<std::size_t, Point>> mouths;
  if (!within.empty()) {
    PathMatrixOptions row;
    row.between_targets = false;
    const PathMatrix through =
        shortest_path_matrix(cspace, *robot_at, within_at, row, cache ? &cache->visibility(narrower) : nullptr);
    plan.stats.segment_tests += through.segment_tests;
    for (std::size_t k = 0; k < within.size(); ++k) {
      if (through.path_from_start[k].empty()) continue;
      if (const auto mouth = gap_mouth(plan_cspace, own_piece, through.path_from_start[k]))
        mouths.emplace_back(within[k], *mouth);
    }
  }
  std::vector<GoalCandidate> kept;
  std::vector<std::size_t> new_index(plan.candidates.size(), 0);
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    new_index[i] = kept.size();
    if (behind[i]) {
      ++plan.stats.candidates_behind_narrow_gaps;
      plan.behind_narrow_gap_points.push_back(plan.candidates[i].frontier_point);
    } else {
      kept.push_back(std::move(plan.candidates[i]));
    }
  }
  plan.candidates = std::move(kept);
  for (auto& [i, mouth] : mouths) i = new_index[i];
  return mouths;
}

}  // namespace

Plan plan_exploration(const TypedMultiPolygon& map, const Pose2& robot, const std::vector<Point>& blacklist,
                      const PlannerOptions& options, const TypedMultiPolygon* passable, const GoalFocus* focus,
                      PlanCache* cache, const DrivenWay* way) {
  Plan plan;
  if (cache) cache->approaches.begin_plan();
  // 1. The C-space, the robot's own node, and the C-space piece it is in: a
  // polygon of the C-space is one connected piece, so only its points are reachable.
  auto setup = set_up(passable ? *passable : map, robot, options, cache, way, plan);
  if (!setup) return plan;
  const ConfigurationSpace& cspace = setup->cspace;
  const Point& robot_point = setup->robot_point;
  const std::optional<Point> start = setup->start;
  const int own_piece = cspace.piece_of(*start);
  plan.stats.robot_in_a_lesser_piece = own_piece >= 0 && is_a_lesser_piece(cspace, own_piece);
  const ObstacleEdges obstacles(map);

  // 2. Candidates on the frontiers, moved into the C-space, or to an
  // approach point when the C-space next to them is cut off from the robot.
  // A candidate is where the robot sees its frontier point from: the nearest
  // C-space point can lie on the other side of a wall (a frontier sliver
  // behind a thin wall, a misaligned scan's free space beyond one), and a
  // robot sent there stands looking at the wall; such a point is dropped and
  // an approach point, which is in view by construction, tried instead.
  auto near_the_blacklist = [&](const Point& p) {
    return std::any_of(blacklist.begin(), blacklist.end(),
                       [&](const Point& b) { return distance(b, p) <= options.blacklist_radius_m; });
  };
  auto chains = frontier_chains(map, &plan.stats.polygons_not_placed);
  if (options.min_enclosed_area_m2 > 0.0 && options.bay_max_area_m2 > 0.0) {
    WalledBayOptions bays;
    bays.max_area_m2 = options.bay_max_area_m2;
    bays.max_lid_m = options.bay_max_lid_m;
    find_walled_bays(map, chains, bays);
  }
  plan.stats.frontier_chains = static_cast<int>(chains.size());
  const auto points = frontier_candidates(chains, options.frontier, &plan.stats.chains_too_short);
  std::vector<Point> targets;
  std::vector<int> pieces;  // per candidate: its C-space piece
  for (const auto& fp : points) {
    // Enclosed first: what lies behind such a frontier is bounded by the
    // map itself, wherever the robot could stand.
    const FrontierChain& chain = chains[static_cast<std::size_t>(fp.chain)];
    if ((chain.enclosed_area_m2 < options.min_enclosed_area_m2 || chain.bay_area_m2 < options.bay_max_area_m2) &&
        !(distance(fp.point, robot_point) <= options.enclosed_goal_range_m) &&
        !(focus && distance(fp.point, focus->frontier) <= focus->radius_m)) {
      ++plan.stats.candidates_enclosed;
      plan.enclosed_frontier_points.push_back(fp.point);
      continue;
    }
    std::optional<Point> position = cspace.nearest_interior_point(fp.point, options.candidate_snap_distance_m);
    bool out_of_view = false;
    if (position && !obstacles.in_view(*position, fp.point)) {
      position.reset();
      out_of_view = true;
    }
    bool approach = false;
    int piece = position ? cspace.piece_of(*position) : -1;
    if (own_piece >= 0 && options.approach_range_m > 0.0 && piece != own_piece) {
      if (auto a = approach_point(cspace, own_piece, fp.point, options.approach_range_m, obstacles,
                                  cache ? &cache->approaches : nullptr)) {
        position = a;
        piece = own_piece;  // an approach point lies in the robot's piece by construction
        approach = true;
        ++plan.stats.approach_candidates;
      }
    }
    // No C-space point near it and no approach point: the nearest C-space
    // point within approach_range_m decides. With a wall between it and the
    // frontier, the frontier is out of view (a sliver beyond a wall, more
    // than the snap distance from the free side). In view, that point is
    // where the robot would see the frontier from: the candidate stands
    // there, in another piece of the C-space than the robot's (an approach
    // point would have been found in the robot's), so it has no path, and
    // the endgame's narrower disk decides whether the gap to that piece is
    // narrower than the robot or about its width (step 5), as for any
    // candidate without a path. (Until session 45 it was "too narrow",
    // which kept the mission from DONE for a frontier at the end of a slot
    // in a room the robot cannot enter: an office floor, docs/exploration.md,
    // "Seen from afar".) With no C-space point within that range it is too
    // narrow.
    if (!position && !out_of_view && options.approach_range_m > 0.0) {
      const auto nearest = cspace.nearest_interior_point(fp.point, options.approach_range_m);
      if (nearest && obstacles.in_view(*nearest, fp.point)) {
        position = nearest;
        piece = cspace.piece_of(*nearest);
        ++plan.stats.candidates_seen_from_afar;
      } else {
        out_of_view = nearest.has_value();
      }
    }
    // A chain's candidate stands at the middle of its arc, and the middle
    // may be hidden where the rest of the arc is not: a room seen through
    // its door at a slant, a cabinet inside the door hiding the middle of
    // the wedge's far frontier (ring2, session 55: the room was never
    // entered). Out of view only if no other point of the arc is in view
    // from the robot's piece of the C-space nearest it. The nearest point
    // only, not a whole approach search per point: most candidates out of
    // view are slivers behind walls, which every plan asks again (the whole
    // search put ring2's plan CPU p50 from 10.4 to 16.2 ms).
    Point frontier_point = fp.point;
    if (!position && out_of_view && own_piece >= 0) {
      for (const Point& f : off_middle_points(chains[static_cast<std::size_t>(fp.chain)].points, fp.arc_from_m,
                                              fp.arc_to_m)) {
        const auto near = cspace.nearest_interior_point(f, options.candidate_snap_distance_m);
        if (near && obstacles.in_view(*near, f) && cspace.piece_of(*near) == own_piece) {
          position = near;
          piece = own_piece;
          approach = true;
          frontier_point = f;
          ++plan.stats.approach_candidates;
          ++plan.stats.approached_off_middle;
          break;
        }
      }
    }
    if (!position && out_of_view) {
      ++plan.stats.candidates_out_of_view;
      plan.out_of_view_frontier_points.push_back(fp.point);
      continue;
    }
    // Only a frontier the robot would be sent to can be a pocket: one with no
    // C-space point near it stays too narrow, which has the mission plan
    // again without the margin (a corridor the margin closes), and that plan
    // decides.
    if (position && options.reach_past_frontier_m > 0.0 &&
        !disk_reaches_past(cspace, obstacles, chains[static_cast<std::size_t>(fp.chain)], fp.arc_from_m, fp.arc_to_m,
                           options.reach_past_frontier_m, options.candidate_snap_distance_m)) {
      ++plan.stats.candidates_in_pockets;
      plan.pocket_frontier_points.push_back(fp.point);
      continue;
    }
    if (!position) {
      ++plan.stats.candidates_not_in_cspace;
      plan.narrow_frontier_points.push_back(fp.point);
      continue;
    }
    GoalCandidate c;
    c.frontier_point = frontier_point;
    c.position = *position;
    c.approach = approach;
    c.chain = fp.chain;
    c.chain_length_m = fp.chain_length_m;
    c.enclosed_area_m2 = chains[static_cast<std::size_t>(fp.chain)].enclosed_or_bay_area_m2();
    c.blacklisted = near_the_blacklist(c.position);
    plan.candidates.push_back(std::move(c));
    targets.push_back(*position);
    pieces.push_back(piece);
  }

  // 3. Shortest paths from the robot and each candidate's cost: path length
  // plus the turn the first leg needs (from the robot's own point, which is
  // outside the C-space when start had to be snapped). The tour needs every
  // path, and between the candidates too: one sparse graph over the reflex
  // vertices (path_matrix.hpp). Greedy needs the cheapest candidate and the
  // followed goal's path only: a lazy search that stops there.
  const double lead_m = distance(robot_point, *start);
  auto cost_of = [&](double length_from_start_m, const std::vector<Point>& path_from_start) {
    const Point& a = lead_m > 0.0 ? robot_point : path_from_start[0];
    const Point& b = lead_m > 0.0 || path_from_start.size() < 2 ? path_from_start[0] : path_from_start[1];
    double turn = 0.0;
    if (distance(a, b) > 1e-9) turn = std::abs(geometry::wrap_angle(std::atan2(b.y() - a.y(), b.x() - a.x()) - robot.theta_rad));
    return length_from_start_m + lead_m + options.turn_cost_m_per_rad * turn;
  };
  // A candidate's shortest path from start, searched: reachable, with its
  // cost, and the path from the robot's own point.
  auto take_path = [&](GoalCandidate& c, double length_from_start_m, std::vector<Point> path_from_start) {
    c.reachable = true;
    c.cost = cost_of(length_from_start_m, path_from_start);
    c.path = std::move(path_from_start);
    c.path_length_m = length_from_start_m + lead_m;
    if (lead_m > 0.0) c.path.insert(c.path.begin(), robot_point);
  };
  // Only candidates in the robot's piece of the C-space are searched for: a
  // search for one it cannot reach never bounds itself and settles the whole
  // graph (the endgame of a large map, where the last frontiers lie in
  // slivers of C-space cut off from the robot's).
  auto searchable = [&](std::size_t i) { return own_piece < 0 || pieces[i] == own_piece; };
  std::vector<char> required;  // the followed goal: its path is wanted whatever the strategy
  if (focus) {
    required.resize(plan.candidates.size());
    for (std::size_t i = 0; i < plan.candidates.size(); ++i)
      required[i] = searchable(i) && focus->matches(plan.candidates[i]);
  }
  PathMatrix matrix;
  VisibilityCache* visibility = cache ? &cache->visibility(options.cspace) : nullptr;
  if (options.strategy == GoalStrategy::kTour && options.tour.horizon_candidates > 0) {
    NearestTargetsQuery query;
    query.count = static_cast<std::size_t>(options.tour.horizon_candidates);
    query.choice.resize(plan.candidates.size());
    for (std::size_t i = 0; i < plan.candidates.size(); ++i)
      query.choice[i] = !plan.candidates[i].blacklisted && searchable(i);
    query.required = required;
    matrix = shortest_paths_among_nearest(cspace, *start, targets, query, visibility);
  } else if (options.strategy == GoalStrategy::kTour) {
    matrix = shortest_path_matrix(cspace, *start, targets, {}, visibility);
  } else {
    CheapestTargetQuery query;
    query.cost = [&](std::size_t i, double length_m, const std::vector<Point>& path) {
      return plan.candidates[i].blacklisted ? std::numeric_limits<double>::infinity() : cost_of(length_m, path);
    };
    query.choice.resize(plan.candidates.size());
    for (std::size_t i = 0; i < plan.candidates.size(); ++i)
      query.choice[i] = !plan.candidates[i].blacklisted && searchable(i);
    query.required = required;
    matrix = shortest_paths_to_cheapest(cspace, *start, targets, query, visibility);
  }
  plan.stats.segment_tests = matrix.segment_tests;
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    auto& c = plan.candidates[i];
    if (!std::isfinite(matrix.from_start_m[i])) {
      // Not searched (greedy stopped at the cheapest): reachable if in the robot's piece.
      c.reachable = !matrix.all_searched && own_piece >= 0 && pieces[i] == own_piece;
      continue;
    }
    take_path(c, matrix.from_start_m[i], std::move(matrix.path_from_start[i]));
  }

  // 4. The goal: the cheapest candidate (greedy), or the first of the
  // shortest open tour from the robot through every candidate (tour).
  // Blacklisted candidates are never goals and not part of the tour.
  if (options.strategy == GoalStrategy::kTour) {
    choose_by_tour(matrix, options.tour, plan);
  } else {
    plan.best = cheapest_goal(plan, [](const GoalCandidate&) { return true; });
  }

  // 5. No goal, and no margin that could be what shuts the robot out:
  // which of the candidates without a path lie behind gaps narrower than
  // the robot, and which behind gaps about its width. Only then (or for the
  // goal followed, when it is one of the latter), so it costs a C-space in
  // the endgame alone (candidates are taken out only when there is no goal:
  // the tour's order is empty then, and no index moves under plan.best).
  if ((plan.best < 0 || focus) && options.narrow_gap_tolerance_m > 0.0 &&
      options.cspace.clearance_margin_m == 0.0 && own_piece >= 0) {
    const auto mouths = settle_behind_narrow_gaps(cspace, passable ? *passable : map, *start, options, focus,
                                                  way, pieces, own_piece, cache, plan);
    // A candidate behind a gap about the robot's width is approached at the
    // gap's mouth: from there the laser sees through the gap, the live view
    // (mission.hpp) opens it as wide as it is, and the next plan goes
    // through if the robot fits. Once: the mouth reached is blacklisted.
    std::vector<Point> views;
    for (const auto& [i, mouth] : mouths) views.push_back(mouth);
    PathMatrixOptions row;
    row.between_targets = false;
    PathMatrix to_mouths;
    if (!views.empty()) to_mouths = shortest_path_matrix(cspace, *start, views, row, visibility);
    plan.stats.segment_tests += to_mouths.segment_tests;
    for (std::size_t k = 0; k < mouths.size(); ++k) {
      if (!std::isfinite(to_mouths.from_start_m[k])) continue;
      auto& c = plan.candidates[mouths[k].first];
      c.position = mouths[k].second;
      c.approach = c.gap_mouth = true;
      c.blacklisted = near_the_blacklist(c.position);
      take_path(c, to_mouths.from_start_m[k], std::move(to_mouths.path_from_start[k]));
      ++plan.stats.gap_mouth_candidates;
    }
    if (plan.best < 0) plan.best = cheapest_goal(plan, [](const GoalCandidate& c) { return c.gap_mouth; });
  }
  plan.ok = true;
  return plan;
}

Plan plan_path_to(const TypedMultiPolygon& map, const Pose2& robot, const Point& target,
                  const PlannerOptions& options, PlanCache* cache, const DrivenWay* way) {
  Plan plan;
  if (!std::isfinite(target.x()) || !std::isfinite(target.y())) {
    plan.error = "target is not finite";
    return plan;
  }
  auto setup = set_up(map, robot, options, cache, way, plan);
  if (!setup) return plan;
  const ConfigurationSpace& cspace = setup->cspace;
  const Point& robot_point = setup->robot_point;
  const std::optional<Point> start = setup->start;
  const auto inside = cspace.nearest_interior_point(target, options.candidate_snap_distance_m);
  if (!inside) {
    ++plan.stats.candidates_not_in_cspace;
    plan.ok = true;  // a valid answer: the target cannot be reached
    return plan;
  }
  GoalCandidate c;
  c.frontier_point = target;
  c.position = *inside;
  const auto paths = shortest_paths(cspace, *start, {*inside});
  plan.stats.segment_tests = paths.segment_tests;
  if (std::isfinite(paths.length_m[0])) {
    c.reachable = true;
    c.path = paths.path[0];
    c.path_length_m = paths.length_m[0];
    if (distance(robot_point, *start) > 0.0) {
      c.path.insert(c.path.begin(), robot_point);
      c.path_length_m += distance(robot_point, *start);
    }
    c.cost = c.path_length_m;
    plan.best = 0;
  }
  plan.candidates.push_back(std::move(c));
  plan.ok = true;
  return plan;
}

}  // namespace pex::planning
