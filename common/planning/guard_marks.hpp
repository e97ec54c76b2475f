#pragma once
// Guard marks: what the scan guard held the robot at, kept for the plans as
// an obstacle the map does not have. The map is a union of the scans' free
// space, so free space seen once stays free: clean glass, which the laser
// sees only near its normal and looks through at a slant, is free in the
// map wherever it was seen through, and a plan routes the robot into it
// again and again. The guard sees the pane when the robot stands before it
// facing it (that is why it holds); a mark keeps those returns out of the
// next plans, as a costmap's obstacle layer keeps the returns of a bumper
// or a sonar, so the path goes round them (through the door beside the
// pane) instead of back into them (docs/exploration.md, "Guard marks").
// A mark is only a hint: it expires (a person who stood in a door walks
// away), and a plan the marks give no way is planned again without them
// (PlanRequest::keep_out_without_marks). Pure: points and times in,
// polygons out; no clock, no I/O.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct GuardMarkOptions {
  // How long a mark is kept (s of the node's clock; 0: no marks).
  double lifetime_s = 300.0;
  // The returns that hold the robot: those the body would touch within this
  // much further driving than the first one on the commanded arc (the
  // patch of a pane seen head-on, not the wall behind it).
  double holding_depth_m = 0.10;
  // And within this of the body (a hold is about what is in front of it).
  double max_reach_m = 0.5;
  // A mark is the returns' convex hull grown by half this (a strip as wide
  // as a keep-out line round a single return).
  double width_m = 0.05;
  // At most this many marks are kept (the oldest go first): each is a
  // polygon every plan takes out of the map.
  int max_marks = 32;
};

// The points (robot frame, heading +x) that hold a robot of body_radius_m
// on the arc of signed curvature curvature_per_m: each point's own
// free_distance_along_arc is within holding_depth_m of the least one, and
// that least one within max_reach_m. Empty when nothing is in the way.
std::vector<mapping::Point> holding_points(std::span<const mapping::Point> points_robot_frame, double curvature_per_m,
                                           double body_radius_m, const GuardMarkOptions& options);

// The marks of a mission, in the map frame, with their times.
class GuardMarks {
 public:
  explicit GuardMarks(GuardMarkOptions options = {}) : options_(options) {}

  // A hold at `robot` (map frame) by `holding` (robot frame, holding_points):
  // one mark more (the oldest dropped beyond max_marks). Returns whether a
  // mark was made (not without points, nor with marks off).
  bool add(std::span<const mapping::Point> holding, const geometry::Pose2& robot, std::int64_t now_utime);
  // Drops the marks older than lifetime_s, and those made after now_utime
  // (taken up from a checkpoint of another clock's run: a rebooted robot,
  // a restarted simulator). Returns how many.
  int expire(std::int64_t now_utime);
  // Drops them all (a new map frame: SLAM restarted).
  void clear();
  std::size_t size() const { return marks_.size(); }
  // The marks with their times, as a sealed archive ("" when there are none),
  // so that a restarted explorer does not drive into the glass again; they
  // are in the map frame of the SLAM epoch the caller keeps beside them.
  std::string checkpoint() const;
  // Takes a checkpoint up in place of the marks held (the newest max_marks
  // of it); "" or why it was refused (then the marks are left as they were).
  std::string restore(std::string_view checkpoint);
  // Every mark as one obstacle area, united with `keep_out` (the operator's,
  // may be null): a new pointer whenever the marks change, the same one in
  // between (planning caches key on it). Null when there are no marks.
  std::shared_ptr<const mapping::TypedMultiPolygon> with_keep_out(
      const std::shared_ptr<const mapping::TypedMultiPolygon>& keep_out);

 private:
  struct Mark {
    mapping::TypedMultiPolygon area;
    std::int64_t utime = 0;
  };
  GuardMarkOptions options_;
  std::vector<Mark> marks_;  // oldest first
  bool changed_ = true;
  std::shared_ptr<const mapping::TypedMultiPolygon> united_, united_keep_out_;
};

}  // namespace pex::planning
