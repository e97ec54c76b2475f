#include "evaluation/relations.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>

namespace pex::evaluation {
namespace {

std::vector<StampedPose> circle_trajectory() {
  std::vector<StampedPose> poses;
  for (int i = 0; i < 50; ++i) {
    const double a = 0.1 * i;
    poses.push_back({100.0 + i, {3.0 * std::cos(a), 3.0 * std::sin(a), geometry::wrap_angle(a + 1.5)}});
  }
  return poses;
}

std::vector<Relation> relations_of(const std::vector<StampedPose>& poses) {
  std::vector<Relation> relations;
  for (std::size_t i = 0; i + 3 < poses.size(); ++i)
    relations.push_back({poses[i].timestamp_s, poses[i + 3].timestamp_s,
                         geometry::relative(poses[i].pose, poses[i + 3].pose)});
  return relations;
}

TEST(Relations, ExactTrajectoryHasZeroError) {
  const auto poses = circle_trajectory();
  const auto result = evaluate_relations(poses, relations_of(poses));
  EXPECT_EQ(result.relations, 47u);
  EXPECT_EQ(result.unmatched, 0u);
  EXPECT_NEAR(result.trans_mean_m, 0.0, 1e-12);
  EXPECT_NEAR(result.rot_mean_deg, 0.0, 1e-9);
}

TEST(Relations, GlobalRigidMotionDoesNotChangeTheError) {
  auto poses = circle_trajectory();
  const auto relations = relations_of(poses);
  for (auto& p : poses) p.pose = geometry::compose({5.0, -2.0, 0.7}, p.pose);
  const auto result = evaluate_relations(poses, relations);
  EXPECT_NEAR(result.trans_mean_m, 0.0, 1e-9);
  EXPECT_NEAR(result.rot_mean_deg, 0.0, 1e-9);
}

TEST(Relations, PerturbedPoseGivesHandComputedError) {
  // Straight line along x, one pose every metre, heading 0; relations between
  // consecutive poses. Pose 2 is moved by +0.3 m in y and turned by 0.1 rad.
  std::vector<StampedPose> poses;
  for (int i = 0; i < 4; ++i) poses.push_back({static_cast<double>(i), {double(i), 0.0, 0.0}});
  std::vector<Relation> relations;
  for (int i = 0; i < 3; ++i) relations.push_back({double(i), double(i + 1), {1.0, 0.0, 0.0}});
  poses[2].pose = {2.0, 0.3, 0.1};
  const auto result = evaluate_relations(poses, relations);
  ASSERT_EQ(result.relations, 3u);
  // Relation 0->1: exact. 1->2: estimated (1, 0.3, 0.1) vs (1,0,0): 0.3 m, 0.1 rad.
  // 2->3: relative of (3,0,0) seen from (2,0.3,0.1): dx=1, dy=-0.3 rotated by -0.1:
  // x' = cos(.1)*1 + sin(.1)*(-0.3), y' = -sin(.1)*1 + cos(.1)*(-0.3), angle -0.1.
  const double x3 = std::cos(0.1) - 0.3 * std::sin(0.1);
  const double y3 = -std::sin(0.1) - 0.3 * std::cos(0.1);
  const double e3 = std::hypot(x3 - 1.0, y3);
  EXPECT_NEAR(result.errors[0].translation_m, 0.0, 1e-12);
  EXPECT_NEAR(result.errors[1].translation_m, 0.3, 1e-12);
  EXPECT_NEAR(result.errors[2].translation_m, e3, 1e-12);
  const double deg = 0.1 * 180.0 / std::numbers::pi;
  EXPECT_NEAR(result.errors[1].rotation_deg, deg, 1e-9);
  EXPECT_NEAR(result.errors[2].rotation_deg, deg, 1e-9);
  const double mean = (0.3 + e3) / 3.0;
  EXPECT_NEAR(result.trans_mean_m, mean, 1e-12);
  const double var = (mean * mean + (0.3 - mean) * (0.3 - mean) + (e3 - mean) * (e3 - mean)) / 3.0;
  EXPECT_NEAR(result.trans_std_m, std::sqrt(var), 1e-12);
  EXPECT_NEAR(result.rot_mean_deg, 2.0 * deg / 3.0, 1e-9);
}

TEST(Relations, RelationsWithoutNearbyPosesAreNotMatched) {
  std::vector<StampedPose> poses = {{0.0, {}}, {1.0, {1.0, 0.0, 0.0}}};
  std::vector<Relation> relations = {{0.0, 1.0, {1.0, 0.0, 0.0}}, {0.0, 5.0, {1.0, 0.0, 0.0}}};
  const auto result = evaluate_relations(poses, relations);
  EXPECT_EQ(result.relations, 1u);
  EXPECT_EQ(result.unmatched, 1u);
}

TEST(Relations, ReadsFilesAndCountsMalformedLines) {
  std::istringstream relations_text(
      "1.5 2.5 0.1 0.2 0 0 0 0.3\n"
      "garbage line\n"
      "1.5 2.5 nan 0.2 0 0 0 0.3\n"
      "\n");
  const auto relations = read_relations(relations_text);
  ASSERT_EQ(relations.relations.size(), 1u);
  EXPECT_EQ(relations.malformed_lines, 2u);
  EXPECT_DOUBLE_EQ(relations.relations[0].pose_2_in_1.theta_rad, 0.3);
  std::istringstream poses_text("# t x y theta\n2 1 1 0\n1 0 0 0\n3 x\n");
  const auto poses = read_poses(poses_text);
  ASSERT_EQ(poses.poses.size(), 2u);
  EXPECT_EQ(poses.malformed_lines, 1u);
  EXPECT_DOUBLE_EQ(poses.poses[0].timestamp_s, 1.0);  // sorted
}

TEST(Relations, JsonLineHasTheAgreedKeys) {
  MetricResult r;
  r.relations = 7;
  r.trans_mean_m = 0.5;
  const std::string json = to_json_line(r);
  EXPECT_EQ(json.find("{\"relations\":7,\"trans_mean_m\":0.500000,\"trans_std_m\":"), 0u);
  EXPECT_NE(json.find("\"rot_std_deg\":"), std::string::npos);
}

}  // namespace
}  // namespace pex::evaluation
