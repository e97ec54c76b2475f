// pex-map and pex-render-map as programs, on a real LCM bus in a private
// network namespace: the map saved from the bus and from a log reads back
// into the identical map, its PGM export is the grid of the same map,
// pex-render-map draws a saved map file, and pex-map check names the maps of
// a log that are not valid.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "harness.hpp"
#include "map_files.hpp"
#include "test_maps.hpp"

namespace pex::map_files {
namespace {

using namespace std::chrono_literals;
using pex::testing::bin_path;
using pex::testing::kTestLcmUrl;
using pex::testing::read_file;
using pex::testing::run_to_completion;

// An LCM log of `maps` on MAP, a second apart; false if it cannot be written.
bool write_map_log(const std::string& path, const std::vector<pex::polygon_map_t>& maps) {
  lcm::LogFile log(path, "w");
  if (!log.good()) return false;
  std::int64_t t = 1'000'000;
  for (const auto& m : maps) {
    std::vector<std::uint8_t> bytes = encoded(m);
    lcm::LogEvent event{};
    event.timestamp = t += 1'000'000;
    event.channel = "MAP";
    event.datalen = static_cast<int32_t>(bytes.size());
    event.data = bytes.data();
    if (log.writeEvent(&event) != 0) return false;
  }
  return true;
}

TEST(MapTool, SaveFromTheBusReadsBackIntoTheIdenticalMap) {
  std::string why;
  ASSERT_TRUE(pex::testing::in_private_netns(&why)) << why;
  const pex::testing::ScratchDir scratch("map-tool-bus");
  const std::string& dir = scratch.path();
  pex::testing::Process save({bin_path("pex-map"), "save", dir + "/bus.geojson", "--lcm-url", kTestLcmUrl,
                              "--timeout-s", "30"},
                             dir + "/save.log");
  // The mapper's part: MAP again and again until pex-map has taken one.
  lcm::LCM lcm(kTestLcmUrl);
  ASSERT_TRUE(lcm.good());
  const auto map = two_rooms_map();
  int exit_code = -2;
  for (int i = 0; i < 600 && exit_code == -2; ++i) {
    lcm.publish("MAP", &map);
    if (const int rc = save.wait(50ms); rc != -1) exit_code = rc;
  }
  ASSERT_EQ(exit_code, 0) << save.output();
  EXPECT_EQ(encoded(from_geojson(read_file(dir + "/bus.geojson"))), encoded(map));

  // The saved file exported and drawn.
  auto r = run_to_completion({bin_path("pex-map"), "export", "--map", dir + "/bus.geojson", "--pgm",
                              dir + "/bus.pgm", "--resolution-m", "0.1", "--margin-m", "0.5"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto grid = from_pgm(read_file(dir + "/bus.pgm"));
  EXPECT_EQ(grid.cells, rasterise(map, 0.1, 0.5).cells);
  EXPECT_NE(read_file(dir + "/bus.yaml").find("image: bus.pgm"), std::string::npos);
  r = run_to_completion({bin_path("pex-render-map"), "--map", dir + "/bus.geojson", "--png", dir + "/bus.png"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rendered 4 rings, 23 vertices"), std::string::npos) << r.output;
}

TEST(MapTool, SaveFromALogTakesItsLastMap) {
  const pex::testing::ScratchDir scratch("map-tool-log");
  const std::string& dir = scratch.path();
  auto older = two_rooms_map();  // one ring fewer
  older.rings.pop_back();
  older.nrings = 3;
  auto last = two_rooms_map();
  ASSERT_TRUE(write_map_log(dir + "/run.lcm", {older, last}));
  const auto r = run_to_completion({bin_path("pex-map"), "save", dir + "/log.geojson", "--log", dir + "/run.lcm"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(encoded(from_geojson(read_file(dir + "/log.geojson"))), encoded(last));
}

// pex-map check on a log: every MAP is checked, each invalid one named, and
// the exit code says whether all were valid.
TEST(MapTool, CheckNamesEveryInvalidMapOfALog) {
  const pex::testing::ScratchDir scratch("map-tool-check");
  const std::string& dir = scratch.path();
  const auto good = two_rooms_map();
  auto crossed = two_rooms_map();  // the island moved onto the rooms
  for (auto& x : crossed.rings[3].x) x -= 18.0;
  crossed.utime = 77;
  ASSERT_TRUE(write_map_log(dir + "/good.lcm", {good, good}));
  ASSERT_TRUE(write_map_log(dir + "/mixed.lcm", {good, crossed, good}));

  auto r = run_to_completion({bin_path("pex-map"), "check", "--log", dir + "/good.lcm"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("checked 2 MAP messages: 0 not valid, 0 undecodable"), std::string::npos) << r.output;

  r = run_to_completion({bin_path("pex-map"), "check", "--log", dir + "/mixed.lcm"});
  EXPECT_EQ(r.exit_code, 65) << r.output;
  EXPECT_NE(r.output.find("not valid: MAP #2 (utime 77"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("checked 3 MAP messages: 1 not valid"), std::string::npos) << r.output;

  // A saved map file is checked as one map.
  ASSERT_EQ(run_to_completion({bin_path("pex-map"), "save", dir + "/good.geojson", "--log", dir + "/good.lcm"})
                .exit_code,
            0);
  r = run_to_completion({bin_path("pex-map"), "check", "--map", dir + "/good.geojson"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("checked 1 MAP message: 0 not valid"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace pex::map_files
