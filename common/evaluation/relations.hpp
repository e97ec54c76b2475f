#pragma once
// The SLAM accuracy metric of Kümmerle et al., "On measuring the accuracy of
// SLAM algorithms", Autonomous Robots 27 (2009): for each reference relation
// (t1, t2, relative pose) the estimated relative pose inverse(P(t1)) ⊕ P(t2) is
// compared with the reference; translational error |dxy| in m and absolute
// rotational error |dθ| in degrees, summarised as mean ± std.
#include <istream>
#include <limits>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"

namespace pex::evaluation {

struct Relation {
  double t1_s = 0.0;
  double t2_s = 0.0;
  geometry::Pose2 pose_2_in_1;  // the pose at t2 expressed in the frame of the pose at t1
};

struct StampedPose {
  double timestamp_s = 0.0;
  geometry::Pose2 pose;
};

// Reads a relations file: one `t1 t2 x y z roll pitch yaw` per line (m, rad);
// z, roll and pitch are ignored. Malformed lines are counted, not fatal.
struct RelationsFile {
  std::vector<Relation> relations;
  std::size_t malformed_lines = 0;
};
RelationsFile read_relations(std::istream& in);

// Reads a trajectory: one `timestamp_s x y theta` per line; '#' lines are skipped.
struct PoseFile {
  std::vector<StampedPose> poses;  // sorted by timestamp on return
  std::size_t malformed_lines = 0;
};
PoseFile read_poses(std::istream& in);

struct MetricOptions {
  // A relation counts only when both of its times have an estimated pose
  // within this many seconds (the pose at the nearest estimated timestamp).
  double max_time_difference_s = 0.05;
  // > 0: the errors are also summarised apart for relations whose times are
  // less than this apart and for the others. Far-apart relations span a loop
  // (closed or not); near ones measure local accuracy.
  double split_gap_s = 0.0;
};

struct ErrorSummary {
  std::size_t relations = 0;
  double trans_mean_m = 0.0;
  double trans_std_m = 0.0;
  double rot_mean_deg = 0.0;
  double rot_std_deg = 0.0;
};

struct RelationError {
  double translation_m = 0.0;
  double rotation_deg = 0.0;  // absolute, >= 0
};

struct MetricResult {
  std::size_t relations = 0;  // matched relations
  std::size_t unmatched = 0;  // relations without estimated poses near t1 or t2
  double trans_mean_m = 0.0;
  double trans_std_m = 0.0;
  double rot_mean_deg = 0.0;
  double rot_std_deg = 0.0;
  std::vector<RelationError> errors;  // per matched relation, in input order
  double split_gap_s = 0.0;           // MetricOptions::split_gap_s; the two below only when > 0
  ErrorSummary near;                  // relations less than split_gap_s apart
  ErrorSummary far;                   // the others
};

// The error of one estimated relative pose against its reference.
RelationError relation_error(const geometry::Pose2& estimated_2_in_1, const geometry::Pose2& reference_2_in_1);

// `poses` must be sorted by timestamp. Std is the population standard deviation.
MetricResult evaluate_relations(const std::vector<StampedPose>& poses,
                                const std::vector<Relation>& relations,
                                const MetricOptions& options = {});

// {"relations":N,"trans_mean_m":..,"trans_std_m":..,"rot_mean_deg":..,"rot_std_deg":..}, with
// "split_gap_s":G,"near":{same fields},"far":{same fields} when split.
std::string to_json_line(const MetricResult& result);

}  // namespace pex::evaluation
