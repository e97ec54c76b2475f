#pragma once
// One exploration step's planning (paper, Algorithm 1 lines "determine goal
// candidates", "plan paths", "evaluate"): C-space of the map, goal candidates
// on the frontiers moved into the C-space, shortest paths from the robot to
// every candidate, and the best candidate: the one with the least path length
// (the paper's cost), with a small tie-break for the turn it needs.
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/scan_polygon.hpp"
#include "planning/cspace.hpp"
#include "planning/frontier_goals.hpp"
#include "planning/goal_tour.hpp"
#include "planning/keep_out.hpp"
#include "planning/pruned_graph.hpp"
#include "planning/visibility_graph.hpp"

namespace pex::planning {

using geometry::Pose2;

// How the goal is chosen among the reachable candidates (the seam of goal
// selection; measured side by side in docs/exploration.md).
enum class GoalStrategy : std::int8_t {
  kGreedy,  // the paper's: the nearest candidate by path length (plus the turn tie-break)
  kTour,    // the first candidate of the shortest open tour from the robot through all of them
};
const char* to_string(GoalStrategy strategy);
// "greedy" / "tour"; nullopt for anything else.
std::optional<GoalStrategy> parse_goal_strategy(std::string_view name);

struct PlannerOptions {
  // The default: in buildings the tour drives 4-15 % less, but on campus it
  // did not, and its plans there take longer than the 20 ms target at p99
  // (docs/exploration.md, "The tour with a horizon of 8 in the daemons").
  GoalStrategy strategy = GoalStrategy::kGreedy;
  TourOptions tour;  // kTour: how hard to look for the shortest order
  CSpaceOptions cspace;
  FrontierGoalOptions frontier;
  // A frontier candidate is moved to the nearest C-space point; farther than
  // this from the frontier and it is dropped (the robot cannot get near that
  // frontier: a gap narrower than the robot). At least the robot radius plus
  // the clearance margin, which is how far the C-space lies from a frontier.
  double candidate_snap_distance_m = 1.0;
  // The robot's own position is moved into the C-space when it is outside
  // (pushed against a wall, map noise) by at most this much.
  double start_snap_distance_m = 0.5;
  // ... but not into a sliver: a C-space piece smaller than this (a speck the
  // live view's or the map's jags cut off beside the robot) when a larger
  // piece is also within start_snap_distance_m, in view of the robot. From a
  // 0.03 m2 sliver 2 cm away every goal had "no path", and the goal followed
  // was given up (floor90, b65's binaries: 58 m back for it at the end). 0: off.
  double start_sliver_area_m2 = 0.05;
  // Candidates within this radius of a blacklisted point are not goals.
  double blacklist_radius_m = 0.5;
  // A frontier whose nearby C-space is cut off from the robot (seen through
  // a door at a grazing angle: the free wedge behind the door is narrower
  // than the robot) is approached instead from the robot's own C-space
  // piece: the nearest point of it within this distance that has the
  // frontier point in view (no obstacle edge of the map between them).
  // 0 = off. Well below the laser's range, so the robot sees the frontier from there.
  double approach_range_m = 8.0;
  // Plans with less than the clearance margin (the mission's tight fallback,
  // a way in, and the plans that follow their goals) also go along the way
  // the robot drove (PlanRequest::trail): the C-space gets the corridor of
  // this half-width about it (driven_trail.hpp). Where the robot's disk has
  // been it fits, whatever a newer map makes of a gap it came through. 0: off.
  double trail_corridor_m = 0.05;
  // Cost = path length + this times the turn the first leg needs (|rad|):
  // among nearly equal paths, prefer the one ahead.
  double turn_cost_m_per_rad = 0.1;
  // A frontier candidate is a goal only if the robot's disk (radius
  // cspace.robot_radius_m) can reach this far past its arc of the frontier,
  // at some point of the arc (sampled every 5 cm), moved there straight from
  // the C-space (from the C-space point nearest the point, or to the place
  // square in front of it from the C-space point nearest that) keeping the
  // radius from every obstacle edge. A
  // frontier no such disk reaches past is a *pocket*: the far side of a gap
  // narrower than the robot (between desks, between a chair's legs, a notch
  // of a ragged wall), into which no visit takes the robot or its laser
  // much further, and where floor the robot could sweep is reached through
  // another frontier, which stays a goal (docs/exploration.md, "Pockets").
  // Pockets are listed, are not goals, and do not keep the mission from
  // DONE. 0 = off (the default: the daemons' missions were no shorter with
  // it, docs/exploration.md): every frontier with a C-space point near it is
  // a goal. 0.02 m is the value measured.
  double reach_past_frontier_m = 0.0;
  // A frontier candidate whose chain borders an unknown region the map
  // encloses (FrontierChain::enclosed_area_m2: a hole of the map, less the
  // map inside it) of less than this is not a goal: no visit can reveal
  // more than that region, and most of it is the object whose unseen side
  // the frontier is (the far side of a desk, a pillar's face, a cabinet seen
  // through a crack). Such frontiers are *enclosed*: listed, not goals, and,
  // like those behind walls, they do not keep the mission from DONE. A chain
  // on the map's outside borders unbounded unknown space and is never
  // enclosed. 0 = off (docs/exploration.md, "Enclosed frontiers").
  double min_enclosed_area_m2 = 0.0;
  // ... except within this straight-line distance of the robot (and the goal
  // it follows, GoalFocus): a look on the way costs little, and it takes the
  // robot deeper into the room it is in; what the rule saves is the trip
  // back for one. 0: none.
  double enclosed_goal_range_m = 0.0;
  // A chain in a walled bay of the map's boundary of less than
  // bay_max_area_m2 (find_walled_bays: the flank of a desk, cabinet or box
  // against a wall, whose front and the wall on both sides the laser saw;
  // the lid, the unseen wall behind the object, at most bay_max_lid_m long)
  // is enclosed as well, on the same terms. Only with min_enclosed_area_m2
  // > 0. bay_max_area_m2 0 = off (docs/exploration.md, "Walled bays").
  double bay_max_area_m2 = 0.0;
  double bay_max_lid_m = 3.0;
  // A plan without the clearance margin that leaves the robot no goal looks
  // once more at the candidates it has no path to (in another piece of its
  // C-space, with no approach point): one whose piece stays apart from the
  // robot's even for a disk this much smaller in radius (no margin, along
  // the way the robot drove as well) lies *behind a gap narrower than the
  // robot* — a room seen through a gap between a cabinet and a wall, the
  // far side of a row of desks. No trip takes the robot or its laser in
  // there, so such frontiers are listed and, like those behind walls, do not
  // keep the mission from DONE. A gap within this much of the robot's width
  // may be the map's noise narrowing a passage it fits through (SLAM's
  // corrections move a door's sides by centimetres): its frontiers get an
  // approach point at the gap's mouth (GoalCandidate::gap_mouth), where the
  // laser sees the gap as wide as it is, once; also for the goal followed
  // (GoalFocus) when the plan has others. Nothing of this while the robot
  // is in a lesser piece of that C-space than its largest (shut in a nook:
  // the mission backs out first). 0 = off (docs/exploration.md, "Behind
  // gaps narrower than the robot").
  double narrow_gap_tolerance_m = 0.0;
};

struct GoalCandidate {
  Point frontier_point;         // on the frontier
  Point position;               // in the C-space: where the robot goes
  // The C-space point next to the frontier is cut off from the robot (or
  // there is none): `position` is instead the nearest point of the robot's
  // own C-space piece from which the frontier point is in view.
  bool approach = false;
  // ... an approach point at the mouth of a gap about the robot's width
  // (PlannerOptions::narrow_gap_tolerance_m): the gap may be a door the map
  // narrowed, and the laser sees it as wide as it is from there.
  bool gap_mouth = false;
  int chain = -1;               // frontier chain index
  double chain_length_m = 0.0;  // length of that frontier chain
  // The unknown region behind that chain, when the map encloses it
  // or a walled bay holds it (FrontierChain::enclosed_or_bay_area_m2); +inf: the map's outside.
  double enclosed_area_m2 = std::numeric_limits<double>::infinity();
  bool blacklisted = false;
  bool reachable = false;       // in the robot's piece of the C-space: a path exists
  // The shortest path, its length and cost (path length plus the turn
  // tie-break). +inf and empty when not reachable, and, with the greedy
  // strategy, for a reachable candidate its search did not need: one that
  // costs more than the goal and is not the focus (plan_exploration).
  double path_length_m = std::numeric_limits<double>::infinity();
  double cost = std::numeric_limits<double>::infinity();
  std::vector<Point> path;      // robot position first, candidate last
};

struct PlanStats {
  int frontier_chains = 0;
  int chains_too_short = 0;
  int candidates_not_in_cspace = 0;  // no C-space point near enough, nor an approach point
  // A C-space point near enough, but with a wall between it and the
  // frontier point, and no approach point: no reachable place sees it.
  int candidates_out_of_view = 0;
  int approach_candidates = 0;       // candidates moved to an approach point (GoalCandidate::approach)
  // Of those, the ones whose middle no place sees, approached at another
  // point of their arc (the candidate's frontier_point is that point).
  int approached_off_middle = 0;
  // No C-space point near enough and no approach point, but one within
  // approach_range_m sees the frontier: the candidate stands there (in
  // another piece than the robot's: no path, unless step 5 settles it).
  int candidates_seen_from_afar = 0;
  int candidates_in_pockets = 0;     // PlannerOptions::reach_past_frontier_m: no disk reaches past them
  int candidates_enclosed = 0;       // PlannerOptions::min_enclosed_area_m2: too little unknown behind them
  int candidates_behind_narrow_gaps = 0;  // PlannerOptions::narrow_gap_tolerance_m
  int gap_mouth_candidates = 0;  // moved to the mouth of a gap about the robot's width (GoalCandidate::gap_mouth)
  // Map polygons whose hole was not looked up (enclosed_areas' work budget,
  // a hostile map): their frontiers and those of the holes around them count
  // as unbounded.
  int polygons_not_placed = 0;
  int cspace_vertices = 0;
  int reflex_nodes = 0;
  // The robot's piece of the C-space is not its largest (a nook the map
  // shut behind it: Mission backs out before it calls the rest unreachable).
  bool robot_in_a_lesser_piece = false;
  int start_sliver_skipped = 0;  // 1: the robot's start moved off a sliver of C-space (start_sliver_area_m2)
  std::int64_t segment_tests = 0;
};

struct Plan {
  bool ok = false;
  std::string error;                    // why not ok
  bool robot_outside_cspace = false;    // not ok because the robot is farther than start_snap_distance_m from it
  std::vector<GoalCandidate> candidates;  // every candidate that got into the C-space
  std::vector<Point> narrow_frontier_points;  // frontier candidates with no C-space point near them
  // Frontier candidates behind a wall: the C-space near them has a wall
  // between it and them, and no point of the robot's piece within
  // approach_range_m has them in view (PlanStats::candidates_out_of_view).
  std::vector<Point> out_of_view_frontier_points;
  // Frontier candidates in pockets (PlannerOptions::reach_past_frontier_m).
  std::vector<Point> pocket_frontier_points;
  // Frontier candidates facing a small enclosed region (PlannerOptions::min_enclosed_area_m2).
  std::vector<Point> enclosed_frontier_points;
  // Frontier candidates behind gaps narrower than the robot
  // (PlannerOptions::narrow_gap_tolerance_m).
  std::vector<Point> behind_narrow_gap_points;
  int best = -1;                        // index into candidates, -1: none reachable
  // kTour: the visiting order (indices into candidates); best is its first,
  // or the nearest when the first is too far (TourOptions::max_first_leg_ratio).
  std::vector<int> tour;
  PlanStats stats;

  int reachable_count() const;
  const GoalCandidate* best_candidate() const { return best >= 0 ? &candidates[static_cast<std::size_t>(best)] : nullptr; }
};

// Whether planning again without the clearance margin may find what this
// plan could not: the robot stands where the margin leaves no room
// (robot_outside_cspace), a frontier has no C-space point near it (too
// narrow), or a candidate that is not blacklisted has no path. A pocket is
// none of these: the margin does not decide it.
bool margin_may_block(const Plan& plan);

// The goal a robot follows (Mission's goal commitment): the candidates the
// mission will take for it — within radius_m of the goal or of its frontier
// point, and not blacklisted — get their paths in every plan, whatever they cost.
struct GoalFocus {
  Point goal;
  Point frontier;
  double radius_m = 0.0;
  // How near c is to the goal: to the goal point or to its frontier point,
  // whichever is nearer. The mission takes the nearest match for its goal.
  double distance_to(const GoalCandidate& c) const;
  bool matches(const GoalCandidate& c) const { return !c.blacklisted && distance_to(c) <= radius_m; }
};

// The approach-point searches of the last plans (exploration_planner.cpp,
// approach_point): per frontier point, the C-space and obstacle edges near it
// that the search depended on, how many boundary points it tried and which
// of them see the frontier point. A plan whose edges near that point are the
// same (the same coordinates, in the same relative order, the same ones in
// the robot's piece) takes the tries from here and only asks again which
// piece each seeing point is in (that depends on the whole map). Late in a
// big mission most frontiers lie behind walls, each failing all its tries
// plan after plan: a fifth of a plan's CPU on campus.
class ApproachCache {
 public:
  struct Memo {
    std::vector<double> cspace_edges;    // a, b and whether in the robot's piece, by edge index
    std::vector<double> obstacle_edges;  // a and b, sorted
    bool filled = false;                 // the edges above are a search's (a new memo's are not)
    std::size_t tried = 0;               // boundary points tried so far, nearest first
    std::vector<Point> seen_from;        // those of them (moved inside) that see the frontier, in order
    std::int64_t last_plan = 0;
  };
  struct Counters {
    std::int64_t kept = 0;      // searches answered from an earlier plan's tries
    std::int64_t searched = 0;  // searched afresh (new frontier point, or its surroundings changed)
  };
  // Once per plan: forgets frontier points the last few plans did not ask about.
  void begin_plan();
  // The memo of frontier point f at this clearance (robot radius plus
  // margin) and range, created empty if there is none.
  Memo& memo(const Point& f, double clearance_m, double range_m);
  void count(bool kept) { ++(kept ? counters_.kept : counters_.searched); }
  Counters counters() const { return counters_; }

 private:
  std::map<std::tuple<double, double, double, double>, Memo> memos_;
  std::int64_t plan_ = 0;
  Counters counters_;
};

// What a planning thread keeps from one plan to the next: plans do not depend
// on it, only their time. One per planning thread (not thread-safe).
class PlanCache {
 public:
  OffsetTileCache offsets;  // the C-space's offset tiles (inward_offset.hpp)
  ApproachCache approaches;  // the approach points' tries
  KeepOutCache keep_out;     // the map without the keep-out (compute_plan)
  // The path graph's segment tests (pruned_graph.hpp), kept per clearance
  // (the mission plans without the margin now and then, and back; a plan
  // with no goal tests the narrow gaps with a narrower disk): the last three
  // clearances asked for.
  VisibilityCache& visibility(const CSpaceOptions& cspace);
  VisibilityCache::Counters visibility_counters() const;  // summed over the clearances

 private:
  struct Slot {
    double clearance_m;
    std::int64_t last_use;
    std::unique_ptr<VisibilityCache> cache;
  };
  std::vector<Slot> slots_;
  std::int64_t uses_ = 0;
  VisibilityCache::Counters dropped_;  // of the slots given up
};

// Plans on `map` (the planning map: free space whose edges are typed obstacle
// or frontier) from `robot`. Candidates near a point of `blacklist` are kept
// in the plan (so a caller can still recognise them) but never chosen.
// `passable`, if given, is where the robot may drive instead of `map` (the
// map opened by the newest scan: live_view.hpp): the C-space is built from
// it, while the frontiers and what is in view of them still come from `map`
// (a live view covers frontiers it has not mapped yet, and its own edges are
// no walls to see through). The greedy strategy searches paths only as far
// as the cheapest candidate and those `focus` matches (shortest_paths_to_cheapest);
// the tour needs them all. Deterministic: the plan is a function of the
// arguments; `cache` (may be null) keeps the C-space's offset tiles and the
// path graph's segment tests from one plan to the next and changes only the
// time taken. `way` (may be null): the way the robot drove, whose corridor
// keeps the C-space open where it joins pieces (ConfigurationSpace::build).
Plan plan_exploration(const TypedMultiPolygon& map, const Pose2& robot, const std::vector<Point>& blacklist,
                      const PlannerOptions& options, const TypedMultiPolygon* passable = nullptr,
                      const GoalFocus* focus = nullptr, PlanCache* cache = nullptr,
                      const DrivenWay* way = nullptr);

// A path from `robot` to `target` (e.g. the mission's start pose) in the
// C-space of `map` (with `way`'s corridor, as plan_exploration): the
// plan's one candidate is `target` moved into the C-space (at most
// candidate_snap_distance_m), best when it is reachable.
Plan plan_path_to(const TypedMultiPolygon& map, const Pose2& robot, const Point& target,
                  const PlannerOptions& options, PlanCache* cache = nullptr,
                  const DrivenWay* way = nullptr);

}  // namespace pex::planning
