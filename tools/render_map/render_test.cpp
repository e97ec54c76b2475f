#include "render.hpp"

#include <cstring>

#include <gtest/gtest.h>

namespace pex::render_map {
namespace {

pex::polygon_ring_t ring(std::vector<double> x, std::vector<double> y, bool hole, std::int8_t type) {
  pex::polygon_ring_t r{};
  r.hole = hole;
  r.nvertices = static_cast<std::int32_t>(x.size());
  r.x = std::move(x);
  r.y = std::move(y);
  r.edge_type.assign(r.x.size(), type);
  return r;
}

pex::polygon_map_t square_with_hole() {
  pex::polygon_map_t m{};
  m.rings.push_back(ring({0, 10, 10, 0}, {0, 0, 10, 10}, false, pex::polygon_ring_t::EDGE_FRONTIER));
  m.rings.push_back(ring({4, 4, 6, 6}, {4, 6, 6, 4}, true, pex::polygon_ring_t::EDGE_OBSTACLE));
  m.nrings = 2;
  return m;
}

TEST(Checksums, KnownValues) {
  // The CRC-32 of "IEND" is in every PNG file: AE 42 60 82.
  const std::uint8_t iend[] = {'I', 'E', 'N', 'D'};
  EXPECT_EQ(crc32(iend, 4), 0xAE426082u);
  // Adler-32 of "Wikipedia" (the worked example of the algorithm).
  const char* w = "Wikipedia";
  EXPECT_EQ(adler32(reinterpret_cast<const std::uint8_t*>(w), std::strlen(w)), 0x11E60398u);
}

TEST(Rasterise, FillsFreeSpaceAndLeavesHolesEmpty) {
  RenderOptions o;
  o.pixels_per_m = 10;
  o.margin_m = 1;
  const auto img = rasterise(square_with_hole(), {}, o);
  EXPECT_EQ(img.width, 120);
  EXPECT_EQ(img.height, 120);
  auto is_white = [&](double x_m, double y_m) {
    const int px = static_cast<int>((x_m + 1) * 10), py = static_cast<int>((11 - y_m) * 10);
    const auto* p = img.at(px, py);
    return p[0] == 255 && p[1] == 255 && p[2] == 255;
  };
  EXPECT_TRUE(is_white(2, 2));
  EXPECT_TRUE(is_white(8, 7));
  EXPECT_FALSE(is_white(5, 5));    // inside the hole
  EXPECT_FALSE(is_white(-0.5, 5));  // outside the map
}

TEST(EncodePng, HasSignatureChunksAndStoredData) {
  Image img;
  img.width = 300;
  img.height = 300;  // > 65535 raw bytes: several stored blocks
  img.rgb.assign(300 * 300 * 3, 7);
  const auto png = encode_png(img);
  const std::uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  ASSERT_GT(png.size(), 300u * 300u * 3u);
  EXPECT_EQ(std::memcmp(png.data(), signature, 8), 0);
  EXPECT_EQ(std::memcmp(png.data() + 12, "IHDR", 4), 0);
  EXPECT_EQ(std::memcmp(png.data() + png.size() - 8, "IEND", 4), 0);
}

TEST(ToSvg, DrawsEveryEdgeAndThePath) {
  const auto svg = to_svg(square_with_hole(), {{1, 1}, {2, 2}}, {});
  std::size_t lines = 0;
  for (std::size_t p = svg.find("<line"); p != std::string::npos; p = svg.find("<line", p + 1)) ++lines;
  EXPECT_EQ(lines, 8u);
  EXPECT_NE(svg.find("evenodd"), std::string::npos);
  EXPECT_NE(svg.find("<polyline"), std::string::npos);
}

}  // namespace
}  // namespace pex::render_map
