// Replay test of pex-slam on real data: the first scans of the Intel Research
// Lab log go through pex-carmen2lcm and `pex-slam --log` (the daemon's own
// handlers), and the trajectory is scored with the relations that fall inside
// that span. The filter must beat raw odometry by a wide margin, and the same
// log and seed must give the same pose file, byte for byte.
//
// FR079 (issue 13): the whole log with the shipped config/slam.toml, its large
// loops closed (docs/slam.md, "Loops of big buildings").
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "evaluation/carmen_log.hpp"
#include "evaluation/relations.hpp"

namespace fs = std::filesystem;
namespace ev = pex::evaluation;

namespace {

constexpr int kScans = 2000;  // the first 395 s of the log: 246 relations, up to 331 s apart

const fs::path kData = fs::path(PEX_SHARED_DIR) / "data";
const fs::path kBin = fs::path(PEX_BINARY_DIR) / "bin";
const fs::path kShippedConfig = fs::path(PEX_SOURCE_DIR) / "config" / "slam.toml";
// The logs' robots over it (their odometry noise: GMapping's motion model).
const fs::path kDatasetsConfig = fs::path(PEX_SOURCE_DIR) / "config" / "datasets" / "slam.toml";

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs `program args` with its output in dir/out.txt, shown when it fails.
int run_in(const fs::path& dir, const fs::path& program, const std::string& args) {
  const std::string command = program.string() + " " + args + " > " + (dir / "out.txt").string() + " 2>&1";
  const int status = std::system(command.c_str());
  if (status != 0) std::cerr << read_file(dir / "out.txt");
  return status;
}

class SlamReplay : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!fs::exists(kData / "intel.clf")) GTEST_SKIP() << "no Intel log in " << kData;
    dir_ = fs::temp_directory_path() / ("pex_slam_replay_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // The head of the log: every line up to the kScans-th FLASER line.
    std::ifstream in(kData / "intel.clf");
    std::ofstream out(dir_ / "head.clf");
    std::string line;
    int scans = 0;
    while (scans < kScans && std::getline(in, line)) {
      out << line << '\n';
      if (line.rfind("FLASER ", 0) == 0) ++scans;
    }
    out.close();
    ASSERT_EQ(scans, kScans);
    ASSERT_EQ(run(kBin / "pex-carmen2lcm", (dir_ / "head.clf").string() + " " + (dir_ / "head.lcm").string()), 0);
    first_poses_ = run_slam("poses_a.txt");
  }
  static void TearDownTestSuite() {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  static int run(const fs::path& program, const std::string& args) { return run_in(dir_, program, args); }
  static fs::path run_slam(const std::string& name) {
    const fs::path poses = dir_ / name;
    EXPECT_EQ(run(kBin / "pex-slam", "--log " + (dir_ / "head.lcm").string() + " --poses " + poses.string() +
                                         " --log-level warn"),
              0);
    return poses;
  }
  static std::vector<ev::Relation> relations_in_span(double t0, double t1) {
    std::ifstream in(kData / "intel.relations");
    std::vector<ev::Relation> inside;
    for (const auto& r : ev::read_relations(in).relations)
      if (r.t1_s >= t0 && r.t2_s <= t1 && r.t2_s >= t0 && r.t1_s <= t1) inside.push_back(r);
    return inside;
  }
  static fs::path dir_;
  static fs::path first_poses_;
};
fs::path SlamReplay::dir_;
fs::path SlamReplay::first_poses_;

TEST_F(SlamReplay, BeatsOdometryOnTheRelationsOfTheSpan) {
  std::ifstream poses_in(first_poses_);
  const auto poses = ev::read_poses(poses_in);
  ASSERT_EQ(poses.malformed_lines, 0u);
  ASSERT_GT(poses.poses.size(), static_cast<std::size_t>(kScans) - 5);  // one line per scan

  // Raw odometry on the same scans, from the log itself.
  std::ifstream clf(dir_ / "head.clf");
  const auto log = ev::parse_carmen_log(clf);
  std::vector<ev::StampedPose> odometry;
  for (const auto& laser : log.lasers) odometry.push_back({laser.timestamp_s, laser.odometry});
  std::stable_sort(odometry.begin(), odometry.end(),
                   [](const auto& a, const auto& b) { return a.timestamp_s < b.timestamp_s; });

  const auto relations = relations_in_span(odometry.front().timestamp_s, odometry.back().timestamp_s);
  ASSERT_GT(relations.size(), 200u);
  const auto slam = ev::evaluate_relations(poses.poses, relations);
  const auto odom = ev::evaluate_relations(odometry, relations);
  EXPECT_EQ(slam.relations, relations.size());
  std::cout << "slam " << ev::to_json_line(slam) << "\nodometry " << ev::to_json_line(odom) << '\n';
  // The bound: the filter meets it with a clear margin, raw odometry fails it.
  constexpr double kBoundM = 0.10;
  EXPECT_LT(slam.trans_mean_m, kBoundM);
  EXPECT_GT(odom.trans_mean_m, kBoundM);
}

TEST_F(SlamReplay, SameLogAndSeedGiveTheSamePoses) {
  const std::string first = read_file(first_poses_);
  const std::string second = read_file(run_slam("poses_b.txt"));
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(first, second);
}

// The whole FR079 log (1061 s, 4934 scans, 1685 relations up to 1038 s apart)
// through pex-carmen2lcm and `pex-slam --log` with the shipped configuration.
// With the odometry as logged (driving backwards counted forwards) the loops
// did not close: 0.205 m (seed 1), 0.691 m (seed 2); with the steps reversed by
// the converter, 0.063 / 0.063 / 0.064 m (seeds 1 / 2 / 3), and 0.054-0.055 m
// with each update's correction spread over the scans before it (the pose
// file since issue 13's third round). 0.10 m is the test's bound, the
// benchmark's figure is in docs/slam.md.
TEST(SlamReplayFr079, ShippedConfigClosesTheLoops) {
  if (!fs::exists(kData / "fr079.clf") || !fs::exists(kData / "fr079.relations"))
    GTEST_SKIP() << "no FR079 log in " << kData;
  const fs::path dir = fs::temp_directory_path() / ("pex_slam_replay_fr079_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // Removed on every way out, a failed ASSERT's too (run_in has printed the
  // failed command's output already).
  struct RemovedOnExit {
    fs::path dir;
    ~RemovedOnExit() {
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  } removed_on_exit{dir};
  ASSERT_EQ(run_in(dir, kBin / "pex-carmen2lcm", (kData / "fr079.clf").string() + " " + (dir / "fr079.lcm").string()), 0);
  ASSERT_EQ(run_in(dir, kBin / "pex-slam", "--config " + kShippedConfig.string() + " --config " + kDatasetsConfig.string() + " --log " +
                                               (dir / "fr079.lcm").string() + " --poses " +
                                               (dir / "poses.txt").string() + " --log-level warn"),
            0);
  std::ifstream poses_in(dir / "poses.txt");
  const auto poses = ev::read_poses(poses_in);
  std::ifstream relations_in(kData / "fr079.relations");
  const auto relations = ev::read_relations(relations_in).relations;
  ASSERT_EQ(poses.malformed_lines, 0u);
  ev::MetricOptions options;
  options.split_gap_s = 100.0;
  const auto slam = ev::evaluate_relations(poses.poses, relations, options);
  std::cout << "fr079 " << ev::to_json_line(slam) << '\n';
  EXPECT_EQ(slam.relations, relations.size());
  EXPECT_LT(slam.trans_mean_m, 0.10);
  EXPECT_LT(slam.far.trans_mean_m, 0.10);  // relations >= 100 s apart: the loops
}

}  // namespace
