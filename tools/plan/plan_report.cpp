#include "plan_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <boost/geometry.hpp>

namespace pex::plan_tool {

namespace bg = boost::geometry;
using mapping::EdgeType;
using mapping::Point;

namespace {

// printf into a string of any length.
std::string format(const char* fmt, auto... args) {
  const int n = std::snprintf(nullptr, 0, fmt, args...);
  std::string out(static_cast<std::size_t>(std::max(n, 0)), '\0');
  std::snprintf(out.data(), out.size() + 1, fmt, args...);
  return out;
}

}  // namespace

std::string describe(const pex::polygon_map_t& map, const pex::pose_t& pose,
                     const planning::ConfigurationSpace& cspace, const planning::Plan& plan) {
  std::string out;
  out += format("map utime %lld: %d vertices; robot at (%.3f, %.3f, %.3f rad), pose utime %lld\n",
                static_cast<long long>(map.utime), static_cast<int>(map.vertex_count), pose.x, pose.y, pose.theta,
                static_cast<long long>(pose.utime));
  if (!plan.ok) {
    out += "plan failed: " + plan.error + "\n";
    return out;
  }
  const Point robot(pose.x, pose.y);
  const auto& pieces = cspace.polygons();
  out += format("C-space: %zu pieces, %d vertices, %d reflex nodes\n", pieces.size(), plan.stats.cspace_vertices,
                plan.stats.reflex_nodes);
  if (plan.stats.start_sliver_skipped > 0)
    out += "start: moved off a sliver of C-space beside the robot (start_sliver_area_m2) to the nearest larger piece\n";
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const double d = bg::distance(robot, pieces[i].geometry);
    out += format("  piece %zu: %.2f m2, %zu holes, %.3f m from the robot%s\n", i, bg::area(pieces[i].geometry),
                  pieces[i].geometry.inners().size(), d, d == 0.0 ? " (the robot's)" : "");
  }
  out += format(
      "frontiers: %d chains (%d too short), %zu candidates, %d approach points, %d seen from afar, %d "
      "with no C-space near, %d out of "
      "view (behind a wall), %d in pockets, %d enclosed, %d behind gaps narrower than the robot, %d approached at "
      "the mouths of gaps about the robot's width\n",
      plan.stats.frontier_chains, plan.stats.chains_too_short, plan.candidates.size(), plan.stats.approach_candidates,
      plan.stats.candidates_seen_from_afar, plan.stats.candidates_not_in_cspace, plan.stats.candidates_out_of_view, plan.stats.candidates_in_pockets,
      plan.stats.candidates_enclosed, plan.stats.candidates_behind_narrow_gaps, plan.stats.gap_mouth_candidates);
  if (plan.stats.polygons_not_placed > 0)
    out += format(
        "  %d map polygons not placed in their holes (work budget): their frontiers and the holes' count as "
        "unbounded\n",
        plan.stats.polygons_not_placed);
  const int robot_piece = cspace.piece_of(robot);
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    const auto& c = plan.candidates[i];
    out += format("  %zu: frontier (%.2f, %.2f) -> (%.2f, %.2f)%s, chain %d (%.2f m", i, c.frontier_point.x(),
                  c.frontier_point.y(), c.position.x(), c.position.y(), c.gap_mouth ? " approach point at a gap's mouth" : c.approach ? " approach point" : "", c.chain,
                  c.chain_length_m);
    out += std::isfinite(c.enclosed_area_m2) ? format(", encloses %.2f m2): ", c.enclosed_area_m2) : std::string("): ");
    if (c.reachable && std::isfinite(c.path_length_m))
      out += format("path %.2f m, cost %.2f%s%s\n", c.path_length_m, c.cost, c.blacklisted ? ", blacklisted" : "",
                    static_cast<int>(i) == plan.best ? "  <- best" : "");
    else if (c.reachable)  // greedy stopped at the goal: this one costs more
      out += format("reachable, path not searched (costs more than the goal)%s\n", c.blacklisted ? ", blacklisted" : "");
    else if (const int piece = cspace.piece_of(c.position); piece >= 0 && piece != robot_piece)
      out += format("no path: in C-space piece %d, not the robot's\n", piece);
    else
      out += "no path\n";
  }
  for (const auto& p : plan.narrow_frontier_points) out += format("  frontier (%.2f, %.2f): too narrow\n", p.x(), p.y());
  for (const auto& p : plan.out_of_view_frontier_points)
    out += format("  frontier (%.2f, %.2f): out of view (no C-space point sees it: behind a wall)\n", p.x(), p.y());
  for (const auto& p : plan.pocket_frontier_points)
    out += format("  frontier (%.2f, %.2f): pocket (no robot reaches past it)\n", p.x(), p.y());
  for (const auto& p : plan.enclosed_frontier_points)
    out += format("  frontier (%.2f, %.2f): enclosed (a small unknown region the map closes in)\n", p.x(), p.y());
  for (const auto& p : plan.behind_narrow_gap_points)
    out += format("  frontier (%.2f, %.2f): behind a gap narrower than the robot\n", p.x(), p.y());
  return out;
}

std::vector<planning::Point> blacklist_of(const pex::explore_state_t& state) {
  std::vector<planning::Point> out;
  const std::size_t n = std::min({state.frontier_x.size(), state.frontier_y.size(), state.frontier_reason.size()});
  for (std::size_t i = 0; i < n; ++i)
    if (state.frontier_reason[i] == pex::explore_state_t::FRONTIER_VISITED ||
        state.frontier_reason[i] == pex::explore_state_t::FRONTIER_GIVEN_UP)
      out.emplace_back(state.frontier_x[i], state.frontier_y[i]);
  return out;
}

std::string to_svg(const mapping::TypedMultiPolygon& map, const geometry::Pose2& robot,
                   const planning::ConfigurationSpace& cspace, const planning::Plan& plan, double pixels_per_m) {
  bg::model::box<Point> box;
  bg::assign_inverse(box);
  for (const auto& p : map) bg::expand(box, bg::return_envelope<bg::model::box<Point>>(p.geometry));
  bg::expand(box, Point(robot.x_m, robot.y_m));
  const double margin = 1.0;
  const double x0 = box.min_corner().x() - margin, y1 = box.max_corner().y() + margin;
  const double w = (box.max_corner().x() - box.min_corner().x() + 2 * margin) * pixels_per_m;
  const double h = (box.max_corner().y() - box.min_corner().y() + 2 * margin) * pixels_per_m;
  auto X = [&](double x) { return (x - x0) * pixels_per_m; };
  auto Y = [&](double y) { return (y1 - y) * pixels_per_m; };
  std::string out = format("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\">\n", w, h);
  out += "<rect width=\"100%\" height=\"100%\" fill=\"#bbbbbb\"/>\n";
  auto polygon_path = [&](const mapping::TypedMultiPolygon& polygons, const char* fill) {
    for (const auto& p : polygons) {
      std::string d;
      auto ring = [&](const mapping::Ring& r) {
        for (std::size_t i = 0; i < r.size(); ++i) d += format("%s%.1f %.1f ", i ? "L" : "M", X(r[i].x()), Y(r[i].y()));
        d += "Z ";
      };
      ring(p.geometry.outer());
      for (const auto& hole : p.geometry.inners()) ring(hole);
      out += format("<path d=\"%s\" fill=\"%s\" fill-rule=\"evenodd\"/>\n", d.c_str(), fill);
    }
  };
  polygon_path(map, "#ffffff");
  polygon_path(cspace.polygons(), "#cfe8cf");
  mapping::for_each_edge(map, [&](const Point& a, const Point& b, EdgeType t) {
    out += format("<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"2\"/>\n", X(a.x()),
                  Y(a.y()), X(b.x()), Y(b.y()), t == EdgeType::kObstacle ? "#000000" : "#ff8800");
  });
  for (std::size_t i = 0; i < plan.candidates.size(); ++i) {
    const auto& c = plan.candidates[i];
    const char* colour = c.reachable ? (static_cast<int>(i) == plan.best ? "#0050ff" : "#00a000") : "#e00000";
    out += format("<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-dasharray=\"3,3\"/>\n",
                  X(c.frontier_point.x()), Y(c.frontier_point.y()), X(c.position.x()), Y(c.position.y()), colour);
    out += format("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"%s\"/>\n", X(c.position.x()), Y(c.position.y()), colour);
    out += format("<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\">%zu</text>\n", X(c.position.x()) + 5,
                  Y(c.position.y()) - 5, i);
  }
  for (const auto& p : plan.narrow_frontier_points)
    out += format("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"none\" stroke=\"#e00000\"/>\n", X(p.x()), Y(p.y()));
  for (const auto& p : plan.pocket_frontier_points)
    out += format("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"none\" stroke=\"#8000c0\"/>\n", X(p.x()), Y(p.y()));
  for (const auto& p : plan.out_of_view_frontier_points)
    out += format("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"none\" stroke=\"#606060\"/>\n", X(p.x()), Y(p.y()));
  for (const auto& p : plan.enclosed_frontier_points)
    out += format("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"none\" stroke=\"#a06000\"/>\n", X(p.x()), Y(p.y()));
  for (const auto& p : plan.behind_narrow_gap_points)
    out += format("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"none\" stroke=\"#c00060\"/>\n", X(p.x()), Y(p.y()));
  if (const auto* best = plan.best_candidate(); best && best->path.size() >= 2) {
    std::string pts;
    for (const auto& p : best->path) pts += format("%.1f,%.1f ", X(p.x()), Y(p.y()));
    out += format("<polyline points=\"%s\" fill=\"none\" stroke=\"#0050ff\" stroke-width=\"2\"/>\n", pts.c_str());
  }
  const double r = cspace.options().robot_radius_m * pixels_per_m;
  out += format("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"none\" stroke=\"#0050ff\"/>\n", X(robot.x_m), Y(robot.y_m), r);
  out += format("<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#0050ff\"/>\n", X(robot.x_m), Y(robot.y_m),
                X(robot.x_m + 0.4 * std::cos(robot.theta_rad)), Y(robot.y_m + 0.4 * std::sin(robot.theta_rad)));
  out += "</svg>\n";
  return out;
}

}  // namespace pex::plan_tool
