// The shipped worlds made from real logs (worlds/intel.wkt, worlds/fr079.wkt,
// made by scripts/make-log-world.sh), read by the simulator's own loader: each
// parses, has its building's size, its START is clear, and a robot disk
// (radius 0.25 m, config/sim.toml) cannot leave it and reaches its rooms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "sim/sim.hpp"

namespace {

using pex::sim::World;

// What each building is, from its log: the size of its walls' box and the
// floor a 0.25 m disk reaches from START (each file's header gives the figure).
struct LogWorld {
  const char* name;
  double min_width_m, max_width_m, min_height_m, max_height_m;
  double min_reached_m2, max_reached_m2;
};

std::ostream& operator<<(std::ostream& out, const LogWorld& w) { return out << w.name; }

class LogWorldTest : public ::testing::TestWithParam<LogWorld> {};

World load(const char* name) {
  const std::string file = std::string(name) + ".wkt";
  const std::string path = std::string(PEX_SOURCE_DIR) + "/worlds/" + file;
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::stringstream text;
  text << in.rdbuf();
  auto result = pex::sim::parse_world(text.str(), file);
  if (auto* e = std::get_if<pex::sim::WorldError>(&result)) {
    ADD_FAILURE() << e->message;
    return {};
  }
  return std::get<World>(std::move(result));
}

TEST_P(LogWorldTest, LoadsWithItsSizeAndAClearStart) {
  const LogWorld& expected = GetParam();
  const World w = load(expected.name);
  ASSERT_FALSE(w.walls.empty());
  EXPECT_GT(w.max_x - w.min_x, expected.min_width_m);
  EXPECT_LT(w.max_x - w.min_x, expected.max_width_m);
  EXPECT_GT(w.max_y - w.min_y, expected.min_height_m);
  EXPECT_LT(w.max_y - w.min_y, expected.max_height_m);
  EXPECT_GT(w.walls.size(), 1000u);  // ragged, not four straight walls
  pex::sim::RayCaster caster(w);
  for (int k = 0; k < 72; ++k) {
    const double a = k * std::numbers::pi / 36;
    const double r = caster.cast(w.start.x_m, w.start.y_m, a, 100.0);
    EXPECT_GT(r, 0.5) << "START too close to a wall at " << a;
    EXPECT_LT(r, 100.0) << "a ray from START leaves the world at " << a;  // closed
  }
}

// The walls rasterised into 5 cm cells, each cell within the robot radius of a
// wall blocked, then a flood fill from START: the robot's centre never gets to
// the edge of the world's bounding box (plus a margin), so it cannot leave;
// and it reaches the building's corridors and rooms.
TEST_P(LogWorldTest, ARobotDiskCannotLeaveAndReachesTheBuilding) {
  const LogWorld& expected = GetParam();
  const World w = load(expected.name);
  ASSERT_FALSE(w.walls.empty());
  constexpr double kCell = 0.05, kRadius = 0.25, kMargin = 1.0;
  const double ox = w.min_x - kMargin, oy = w.min_y - kMargin;
  const int width = static_cast<int>(std::ceil((w.max_x - w.min_x + 2 * kMargin) / kCell));
  const int height = static_cast<int>(std::ceil((w.max_y - w.min_y + 2 * kMargin) / kCell));
  std::vector<std::uint8_t> blocked(static_cast<std::size_t>(width) * height, 0);
  // Block every cell centre within the radius (less half a cell's diagonal,
  // so the test does not close gaps the disk really passes) of a wall.
  const double reach = kRadius - 0.5 * kCell * std::numbers::sqrt2;
  const int pad = static_cast<int>(std::ceil(kRadius / kCell)) + 1;
  for (const auto& s : w.walls) {
    const int x0 = static_cast<int>(std::floor((std::min(s.x0, s.x1) - ox) / kCell)) - pad;
    const int x1 = static_cast<int>(std::floor((std::max(s.x0, s.x1) - ox) / kCell)) + pad;
    const int y0 = static_cast<int>(std::floor((std::min(s.y0, s.y1) - oy) / kCell)) - pad;
    const int y1 = static_cast<int>(std::floor((std::max(s.y0, s.y1) - oy) / kCell)) + pad;
    const double vx = s.x1 - s.x0, vy = s.y1 - s.y0, len2 = vx * vx + vy * vy;
    for (int y = std::max(0, y0); y <= std::min(height - 1, y1); ++y) {
      for (int x = std::max(0, x0); x <= std::min(width - 1, x1); ++x) {
        const double px = ox + (x + 0.5) * kCell, py = oy + (y + 0.5) * kCell;
        const double t = len2 > 0 ? std::clamp(((px - s.x0) * vx + (py - s.y0) * vy) / len2, 0.0, 1.0) : 0.0;
        if (std::hypot(px - s.x0 - t * vx, py - s.y0 - t * vy) < reach) blocked[static_cast<std::size_t>(y) * width + x] = 1;
      }
    }
  }
  const int sx = static_cast<int>((w.start.x_m - ox) / kCell), sy = static_cast<int>((w.start.y_m - oy) / kCell);
  std::vector<std::uint8_t> seen(blocked.size(), 0);
  std::vector<int> stack{sy * width + sx};
  seen[stack.back()] = 1;
  std::size_t cells = 0;
  bool escaped = false;
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    ++cells;
    const int cx = c % width, cy = c / width;
    if (cx == 0 || cy == 0 || cx == width - 1 || cy == height - 1) {
      escaped = true;
      continue;
    }
    for (const int n : {c - 1, c + 1, c - width, c + width}) {
      if (seen[n] || blocked[n]) continue;
      seen[n] = 1;
      stack.push_back(n);
    }
  }
  EXPECT_FALSE(escaped);
  const double area = static_cast<double>(cells) * kCell * kCell;
  EXPECT_GT(area, expected.min_reached_m2);
  EXPECT_LT(area, expected.max_reached_m2);
}

INSTANTIATE_TEST_SUITE_P(
    Shipped, LogWorldTest,
    ::testing::Values(
        // The Intel lab: about 29 × 29 m; the loop corridor and most rooms
        // (its header: a disk's centre reaches about 343 m²).
        LogWorld{"intel", 25.0, 35.0, 25.0, 35.0, 250.0, 600.0},
        // FR079: a 40 m corridor with offices on both sides, 16 m deep (its
        // header: about 234 m²).
        LogWorld{"fr079", 35.0, 45.0, 12.0, 20.0, 180.0, 400.0}),
    [](const ::testing::TestParamInfo<LogWorld>& info) { return std::string(info.param.name); });

}  // namespace
