// Map files: GeoJSON reads back into the identical MAP message; the PGM
// export of the two-rooms map is the polygons rasterised; bad files are
// refused with where and why.
#include "map_files.hpp"

#include "test_maps.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <boost/geometry.hpp>
#include <gtest/gtest.h>

namespace pex::map_files {
namespace {

namespace bg = boost::geometry;
using Point = bg::model::d2::point_xy<double>;
using Polygon = bg::model::polygon<Point, false, true>;  // CCW outer, closed
using Segment = bg::model::segment<Point>;

TEST(MapFiles, GeoJsonReadsBackIntoTheIdenticalMap) {
  const auto map = two_rooms_map();
  const std::string text = to_geojson(map);
  const auto back = from_geojson(text);
  EXPECT_EQ(encoded(back), encoded(map));  // every field, every double bit for bit
  EXPECT_EQ(to_geojson(back), text);
}

TEST(MapFiles, GeoJsonIsAFeatureCollectionOfPolygonsWithEdgeTypes) {
  const std::string text = to_geojson(two_rooms_map());
  EXPECT_NE(text.find("\"type\": \"FeatureCollection\""), std::string::npos);
  EXPECT_NE(text.find("\"type\": \"Polygon\""), std::string::npos);
  EXPECT_NE(text.find("\"frontier\""), std::string::npos);
  EXPECT_NE(text.find("\"frame\": \"map\""), std::string::npos);
}

TEST(MapFiles, BadFilesAreRefusedSayingWhereAndWhy) {
  const std::string good = to_geojson(two_rooms_map());
  const auto refused = [](const std::string& text) -> std::string {
    try {
      from_geojson(text);
    } catch (const MapFileError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(refused("not json").find("not JSON"), std::string::npos);
  EXPECT_NE(refused("{\"type\": \"Feature\"}").find("FeatureCollection"), std::string::npos);
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return t.replace(at, from.size(), to);
  };
  EXPECT_NE(refused(replace("\"frontier\"", "\"door\"")).find("features[0] ring 0"), std::string::npos);
  EXPECT_NE(refused(replace("\"pex_map_format\": 1", "\"pex_map_format\": 2")).find("pex_map_format 2"),
            std::string::npos);
  EXPECT_NE(refused(replace("\"obstacle\",", "")).find("edge_types has"), std::string::npos);
  EXPECT_NE(refused(replace("\"scan_utime\"", "\"scan_time\"")).find("no \"scan_utime\""), std::string::npos);

  // A map whose hole comes before its outer ring cannot be written.
  auto bad = two_rooms_map();
  std::swap(bad.rings[0], bad.rings[1]);
  EXPECT_THROW(to_geojson(bad), MapFileError);
  bad = two_rooms_map();
  bad.rings[3].x[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(to_geojson(bad), MapFileError);
}

// What pex-map check reports: a map the mapper may not publish. Each case
// breaks the two-rooms map in one way; the map itself is valid.
TEST(MapFiles, GeometryProblemFindsWhatIsNotAValidMultiPolygon) {
  EXPECT_EQ(geometry_problem(two_rooms_map()), "");
  auto broken = [](auto&& change) {
    auto m = two_rooms_map();
    change(m);
    return geometry_problem(m);
  };
  const std::vector<std::int8_t> four(4, kObstacle);
  // A hole that crosses itself (a bow tie).
  EXPECT_NE(broken([&](pex::polygon_map_t& m) {
              m.rings[1] = ring(0, true, {{8.5, 2}, {9.3, 2.8}, {8.5, 2.8}, {9.3, 2}}, four);
            }),
            "");
  // A hole outside its polygon.
  EXPECT_NE(broken([&](pex::polygon_map_t& m) {
              m.rings[1] = ring(0, true, {{14, 2}, {14, 3}, {15, 3}, {15, 2}}, four);
            }),
            "");
  // The island moved onto the rooms: two polygons overlap.
  EXPECT_NE(broken([](pex::polygon_map_t& m) {
              for (auto& x : m.rings[3].x) x -= 18.0;
            }),
            "");
  // The outer ring clockwise.
  EXPECT_NE(broken([](pex::polygon_map_t& m) {
              std::reverse(m.rings[0].x.begin(), m.rings[0].x.end());
              std::reverse(m.rings[0].y.begin(), m.rings[0].y.end());
            }),
            "");
  // check_map's reason comes first.
  EXPECT_NE(broken([](pex::polygon_map_t& m) { m.nrings = 9; }).find("nrings 9"), std::string::npos);
}

TEST(MapFiles, PgmReadsBackIntoTheSameGrid) {
  const auto grid = rasterise(two_rooms_map(), 0.1, 0.5);
  const auto back = from_pgm(to_pgm(grid));
  EXPECT_EQ(back.width, grid.width);
  EXPECT_EQ(back.height, grid.height);
  EXPECT_EQ(back.cells, grid.cells);
  const std::string yaml = to_yaml(grid, "two_rooms.pgm");
  EXPECT_NE(yaml.find("image: two_rooms.pgm\n"), std::string::npos);
  EXPECT_NE(yaml.find("resolution: 0.10000000000000001\n"), std::string::npos);
  EXPECT_NE(yaml.find("origin: [-0.5, -0.5, 0.0]\n"), std::string::npos);
  EXPECT_THROW(from_pgm("P2\n1 1\n255\n\x01"), MapFileError);
  EXPECT_THROW(from_pgm("P5\n2 2\n255\n\x01"), MapFileError);  // 1 byte of 4
}

// Distance from a cell's centre to the nearest edge of the given type (-1: any).
double distance_to_edges(const pex::polygon_map_t& map, const Point& p, int type) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& r : map.rings)
    for (std::size_t i = 0; i < r.x.size(); ++i) {
      if (type >= 0 && r.edge_type[i] != type) continue;
      const std::size_t j = (i + 1) % r.x.size();
      best = std::min(best, bg::distance(p, Segment{{r.x[i], r.y[i]}, {r.x[j], r.y[j]}}));
    }
  return best;
}

TEST(MapFiles, PgmOfTheTwoRoomsMapIsItsPolygonsRasterised) {
  const auto map = two_rooms_map();
  // The free space with Boost.Geometry, independent of the exporter's scanlines.
  std::vector<Polygon> polygons;
  for (const auto& r : map.rings) {
    if (!r.hole) polygons.emplace_back();
    auto& target = r.hole ? (polygons.back().inners().emplace_back(), polygons.back().inners().back())
                          : polygons.back().outer();
    for (std::size_t i = 0; i < r.x.size(); ++i) target.push_back({r.x[i], r.y[i]});
    target.push_back({r.x[0], r.y[0]});
  }
  for (auto& p : polygons) bg::correct(p);
  const double res = 0.05;
  const auto grid = from_pgm(to_pgm(rasterise(map, res, 0.5)));  // as a reader of the file sees it
  const auto placed = rasterise(map, res, 0.5);                    // for the cells' coordinates
  ASSERT_NEAR(grid.width, (21.7 + 1.0) / res, 1.0);  // 0 .. 21.7 m plus the margins
  ASSERT_NEAR(grid.height, (7.0 + 1.0) / res, 1.0);
  int free = 0, occupied = 0, checked = 0;
  for (int row = 0; row < grid.height; ++row)
    for (int col = 0; col < grid.width; ++col) {
      const Point centre{placed.x_of(col), placed.y_of(row)};
      const auto cell = grid.at(col, row);
      const double to_obstacle = distance_to_edges(map, centre, kObstacle);
      const double to_any = distance_to_edges(map, centre, -1);
      bool inside = false;
      for (const auto& p : polygons) inside = inside || bg::within(centre, p);
      if (cell == OccupancyGrid::kOccupied) {
        ++occupied;
        // Only cells an obstacle edge passes through: their centre is at most half a diagonal from it.
        ASSERT_LE(to_obstacle, res * std::sqrt(0.5) + 1e-9) << "col " << col << " row " << row;
      } else if (to_obstacle < 0.49 * res) {
        FAIL() << "an obstacle edge passes through col " << col << " row " << row << " but it is " << int(cell);
      }
      if (to_any > 0.75 * res) {  // well inside or outside: exactly the polygons
        ++checked;
        ASSERT_EQ(cell, inside ? OccupancyGrid::kFree : OccupancyGrid::kUnknown)
            << "col " << col << " row " << row << " at " << centre.x() << ", " << centre.y();
      }
      free += cell == OccupancyGrid::kFree;
    }
  // The free cells cover the free area (82.66 m^2 less the 10 cm wall, plus the island) to a few cells.
  const double area = bg::area(polygons[0]) + bg::area(polygons[1]);
  EXPECT_NEAR(free * res * res, area, 0.06 * area);
  double obstacle_m = 0.0;
  for (const auto& r : map.rings)
    for (std::size_t i = 0; i < r.x.size(); ++i)
      if (r.edge_type[i] == kObstacle) {
        const std::size_t j = (i + 1) % r.x.size();
        obstacle_m += std::hypot(r.x[j] - r.x[i], r.y[j] - r.y[i]);
      }
  EXPECT_GT(occupied, 0.9 * obstacle_m / res);  // every wall drawn
  EXPECT_GT(checked, grid.width * grid.height / 2);
}

TEST(MapFiles, RasteriseRefusesAResolutionOfZeroAndHugeGrids) {
  EXPECT_THROW(rasterise(two_rooms_map(), 0.0), MapFileError);
  EXPECT_THROW(rasterise(two_rooms_map(), 1e-4, 0.5, 1'000'000), MapFileError);
}

}  // namespace
}  // namespace pex::map_files
