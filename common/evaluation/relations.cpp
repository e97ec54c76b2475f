#include "evaluation/relations.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

namespace pex::evaluation {
namespace {

bool all_finite(const double* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

bool skip_line(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

// Index of the pose with the nearest timestamp, or npos when farther than max_dt.
std::size_t nearest(const std::vector<StampedPose>& poses, double t, double max_dt) {
  if (poses.empty()) return std::string::npos;
  auto it = std::lower_bound(poses.begin(), poses.end(), t,
                             [](const StampedPose& p, double v) { return p.timestamp_s < v; });
  std::size_t best = std::string::npos;
  double best_dt = std::numeric_limits<double>::infinity();
  for (auto candidate : {it, it == poses.begin() ? it : it - 1}) {
    if (candidate == poses.end()) continue;
    const double dt = std::abs(candidate->timestamp_s - t);
    if (dt < best_dt) {
      best_dt = dt;
      best = static_cast<std::size_t>(candidate - poses.begin());
    }
  }
  return best_dt <= max_dt ? best : std::string::npos;
}

void mean_std(const std::vector<double>& v, double& mean, double& stddev) {
  mean = 0.0;
  stddev = 0.0;
  if (v.empty()) return;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double var = 0.0;
  for (double x : v) var += (x - mean) * (x - mean);
  stddev = std::sqrt(var / static_cast<double>(v.size()));
}

}  // namespace

RelationsFile read_relations(std::istream& in) {
  RelationsFile file;
  std::string line;
  while (std::getline(in, line)) {
    if (skip_line(line)) continue;
    std::istringstream fields(line);
    double v[8];
    bool ok = true;
    for (double& x : v) ok = ok && static_cast<bool>(fields >> x);
    if (!ok || !all_finite(v, 8)) {
      ++file.malformed_lines;
      continue;
    }
    file.relations.push_back({v[0], v[1], {v[2], v[3], geometry::wrap_angle(v[7])}});
  }
  return file;
}

PoseFile read_poses(std::istream& in) {
  PoseFile file;
  std::string line;
  while (std::getline(in, line)) {
    if (skip_line(line)) continue;
    std::istringstream fields(line);
    double v[4];
    bool ok = true;
    for (double& x : v) ok = ok && static_cast<bool>(fields >> x);
    if (!ok || !all_finite(v, 4)) {
      ++file.malformed_lines;
      continue;
    }
    file.poses.push_back({v[0], {v[1], v[2], v[3]}});
  }
  std::stable_sort(file.poses.begin(), file.poses.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.timestamp_s < b.timestamp_s; });
  return file;
}

RelationError relation_error(const geometry::Pose2& estimated, const geometry::Pose2& reference) {
  const geometry::Pose2 error = geometry::relative(reference, estimated);
  return {std::hypot(error.x_m, error.y_m),
          std::abs(geometry::wrap_angle(error.theta_rad)) * 180.0 / std::numbers::pi};
}

MetricResult evaluate_relations(const std::vector<StampedPose>& poses,
                                const std::vector<Relation>& relations,
                                const MetricOptions& options) {
  MetricResult result;
  result.split_gap_s = options.split_gap_s;
  std::vector<double> trans, rot, near_trans, near_rot, far_trans, far_rot;
  for (const Relation& relation : relations) {
    const std::size_t i1 = nearest(poses, relation.t1_s, options.max_time_difference_s);
    const std::size_t i2 = nearest(poses, relation.t2_s, options.max_time_difference_s);
    if (i1 == std::string::npos || i2 == std::string::npos) {
      ++result.unmatched;
      continue;
    }
    const geometry::Pose2 estimated = geometry::relative(poses[i1].pose, poses[i2].pose);
    const RelationError error = relation_error(estimated, relation.pose_2_in_1);
    result.errors.push_back(error);
    trans.push_back(error.translation_m);
    rot.push_back(error.rotation_deg);
    const bool near = std::abs(relation.t2_s - relation.t1_s) < options.split_gap_s;
    (near ? near_trans : far_trans).push_back(error.translation_m);
    (near ? near_rot : far_rot).push_back(error.rotation_deg);
  }
  result.relations = result.errors.size();
  mean_std(trans, result.trans_mean_m, result.trans_std_m);
  mean_std(rot, result.rot_mean_deg, result.rot_std_deg);
  auto summarise = [](const std::vector<double>& t, const std::vector<double>& r, ErrorSummary& out) {
    out.relations = t.size();
    mean_std(t, out.trans_mean_m, out.trans_std_m);
    mean_std(r, out.rot_mean_deg, out.rot_std_deg);
  };
  summarise(near_trans, near_rot, result.near);
  summarise(far_trans, far_rot, result.far);
  return result;
}

namespace {

std::string summary_fields(std::size_t relations, double trans_mean, double trans_std, double rot_mean,
                           double rot_std) {
  char buffer[192];
  std::snprintf(buffer, sizeof buffer,
                "\"relations\":%zu,\"trans_mean_m\":%.6f,\"trans_std_m\":%.6f,"
                "\"rot_mean_deg\":%.6f,\"rot_std_deg\":%.6f",
                relations, trans_mean, trans_std, rot_mean, rot_std);
  return buffer;
}

std::string summary_fields(const ErrorSummary& s) {
  return summary_fields(s.relations, s.trans_mean_m, s.trans_std_m, s.rot_mean_deg, s.rot_std_deg);
}

}  // namespace

std::string to_json_line(const MetricResult& r) {
  std::string json = "{" + summary_fields(r.relations, r.trans_mean_m, r.trans_std_m, r.rot_mean_deg, r.rot_std_deg);
  if (r.split_gap_s > 0.0) {
    char gap[64];
    std::snprintf(gap, sizeof gap, ",\"split_gap_s\":%g", r.split_gap_s);
    json += gap;
    json += ",\"near\":{" + summary_fields(r.near) + "},\"far\":{" + summary_fields(r.far) + "}";
  }
  return json + "}";
}

}  // namespace pex::evaluation
