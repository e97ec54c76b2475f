#include "mapping/map_archive.hpp"

#include <random>

#include <gtest/gtest.h>

#include "mapping/scan_polygon.hpp"
#include "mapping/test_support.hpp"

namespace pex::mapping {
namespace {

using geometry::Pose2;

// A map of a random room with pillars, scanned along a line: several tiles,
// holes, all three edge types.
PolygonMap scanned_room(const PolygonMapOptions& options = {}) {
  std::mt19937_64 rng(7);
  const auto walls = testing::random_room(20.0, 12.0, 4, rng);
  const testing::ScanSpec spec;
  PolygonMap map(options);
  ScanPolygonOptions scan_options;
  scan_options.range_max_m = spec.range_max_m;
  for (int i = 0; i < 12; ++i) {
    const Pose2 pose{2.0 + 1.3 * i, 6.0 + 0.2 * (i % 3), 0.4 * i};
    const auto scan = scan_to_polygon(testing::cast_scan(walls, pose, spec, 0.01, &rng), spec.angle_min,
                                      spec.angle_increment, pose, scan_options);
    EXPECT_TRUE(scan.ok) << scan.error;
    map.insert(scan.polygon);
  }
  return map;
}

bool same_geometry(const TypedMultiPolygon& a, const TypedMultiPolygon& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].edge_types != b[i].edge_types) return false;
    if (!bg::equals(a[i].geometry, b[i].geometry)) return false;
    // Point for point, not only the same set.
    if (a[i].geometry.outer().size() != b[i].geometry.outer().size()) return false;
    for (std::size_t k = 0; k < a[i].geometry.outer().size(); ++k)
      if (a[i].geometry.outer()[k].x() != b[i].geometry.outer()[k].x() ||
          a[i].geometry.outer()[k].y() != b[i].geometry.outer()[k].y())
        return false;
  }
  return true;
}

std::string saved(const PolygonMap& map) {
  archive::ByteWriter out;
  write_polygon_map(out, map);
  return out.take();
}

TEST(MapArchive, ARestoredMapIsTheSavedMapTileForTileAndPlansTheSame) {
  const PolygonMap map = scanned_room();
  ASSERT_GT(map.tile_count(), 2u);
  const std::string bytes = saved(map);
  archive::ByteReader in(bytes);
  const PolygonMap restored = read_polygon_map(in, map.options());
  in.expect_end();
  ASSERT_EQ(restored.tile_count(), map.tile_count());
  EXPECT_EQ(restored.scans_inserted(), map.scans_inserted());
  for (const auto& [key, tile] : map.tiles()) {
    const auto& other = restored.tiles().at(key);
    EXPECT_TRUE(same_geometry(tile->free, other->free));
    EXPECT_TRUE(same_geometry(tile->obstacles, other->obstacles));
  }
  const auto a = map.planning_map(), b = restored.planning_map();
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_TRUE(same_geometry(a.polygons, b.polygons));
  EXPECT_GT(area(b.polygons), 50.0);
  // And it goes on as the original: the same scan into both, the same map.
  PolygonMap original = map, continued = restored;
  std::mt19937_64 rng(3);
  const auto walls = testing::random_room(20.0, 12.0, 4, rng);
  const testing::ScanSpec spec;
  ScanPolygonOptions scan_options;
  scan_options.range_max_m = spec.range_max_m;
  const Pose2 pose{10.0, 3.0, 1.0};
  const auto scan = scan_to_polygon(testing::cast_scan(walls, pose, spec), spec.angle_min, spec.angle_increment,
                                    pose, scan_options);
  ASSERT_TRUE(scan.ok);
  original.insert(scan.polygon);
  continued.insert(scan.polygon);
  EXPECT_TRUE(same_geometry(original.planning_map().polygons, continued.planning_map().polygons));
}

TEST(MapArchive, AnotherTileGridIsRefused) {
  const PolygonMap map = scanned_room();
  const std::string bytes = saved(map);
  PolygonMapOptions other = map.options();
  other.tile_size_m = 4.0;
  archive::ByteReader in(bytes);
  EXPECT_THROW(read_polygon_map(in, other), archive::ArchiveError);
}

TEST(MapArchive, DamagedGeometryIsRefusedNotHalfRead) {
  // A square whose vertex is moved so the ring crosses itself.
  TypedPolygon bowtie;
  bg::append(bowtie.geometry.outer(), Point(0, 0));
  bg::append(bowtie.geometry.outer(), Point(1, 1));
  bg::append(bowtie.geometry.outer(), Point(1, 0));
  bg::append(bowtie.geometry.outer(), Point(0, 1));
  bg::append(bowtie.geometry.outer(), Point(0, 0));
  bowtie.edge_types = {{EdgeType::kObstacle, EdgeType::kObstacle, EdgeType::kFrontier, EdgeType::kFrontier}};
  archive::ByteWriter out;
  write_typed_multipolygon(out, {bowtie});
  archive::ByteReader in(out.bytes());
  EXPECT_THROW(read_typed_multipolygon(in, "test"), archive::ArchiveError);

  // An unknown edge type byte.
  TypedPolygon square;
  for (auto [x, y] : {std::pair{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}}) bg::append(square.geometry.outer(), Point(x, y));
  square.edge_types = {{EdgeType::kObstacle, EdgeType::kObstacle, EdgeType::kObstacle, EdgeType::kObstacle}};
  archive::ByteWriter good;
  write_typed_multipolygon(good, {square});
  {
    archive::ByteReader ok(good.bytes());
    EXPECT_EQ(read_typed_multipolygon(ok, "square").size(), 1u);
  }
  std::string bad = good.bytes();
  bad.back() = 7;
  archive::ByteReader in2(bad);
  EXPECT_THROW(read_typed_multipolygon(in2, "square"), archive::ArchiveError);
}

}  // namespace
}  // namespace pex::mapping
