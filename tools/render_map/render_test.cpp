#include "render.hpp"

#include <cairo.h>
#include <fontconfig/fontconfig.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <set>
#include <string>

#include <gtest/gtest.h>

namespace pex::render_map {
namespace {

constexpr double kPi = 3.14159265358979323846;

pex::polygon_ring_t ring(std::vector<double> x, std::vector<double> y, bool hole, std::int8_t type) {
  pex::polygon_ring_t r{};
  r.hole = hole;
  r.nvertices = static_cast<std::int32_t>(x.size());
  r.x = std::move(x);
  r.y = std::move(y);
  r.edge_type.assign(r.x.size(), type);
  return r;
}

// A 10 m square: obstacle walls but for the frontier on its top side (y = 10), and an
// obstacle hole 4..6 x 4..6.
pex::polygon_map_t square_with_hole() {
  pex::polygon_map_t m{};
  auto outer = ring({0, 10, 10, 0}, {0, 0, 10, 10}, false, pex::polygon_ring_t::EDGE_OBSTACLE);
  outer.edge_type[2] = pex::polygon_ring_t::EDGE_FRONTIER;  // (10,10) -> (0,10)
  m.rings.push_back(outer);
  m.rings.push_back(ring({4, 4, 6, 6}, {4, 6, 6, 4}, true, pex::polygon_ring_t::EDGE_OBSTACLE));
  m.nrings = 2;
  return m;
}

// The same map turned by `rad` about the origin.
pex::polygon_map_t turned(pex::polygon_map_t m, double rad) {
  for (auto& r : m.rings)
    for (std::size_t i = 0; i < r.x.size(); ++i) {
      const double x = r.x[i], y = r.y[i];
      r.x[i] = std::cos(rad) * x - std::sin(rad) * y;
      r.y[i] = std::sin(rad) * x + std::cos(rad) * y;
    }
  return m;
}

// A PNG decoded by cairo (libpng), as a person's viewer would.
struct Decoded {
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface{nullptr, cairo_surface_destroy};
  int width = 0, height = 0;
  Rgb at(double x, double y) const {
    const int stride = cairo_image_surface_get_stride(surface.get());
    const auto* row = cairo_image_surface_get_data(surface.get()) + static_cast<std::size_t>(y) * stride;
    const std::uint32_t p = reinterpret_cast<const std::uint32_t*>(row)[static_cast<int>(x)];
    return {static_cast<std::uint8_t>(p >> 16), static_cast<std::uint8_t>(p >> 8), static_cast<std::uint8_t>(p)};
  }
};

Decoded decode(const std::vector<std::uint8_t>& png) {
  struct Reader {
    const std::vector<std::uint8_t>* data;
    std::size_t pos = 0;
  } reader{&png};
  auto read = [](void* closure, unsigned char* out, unsigned int length) {
    auto* r = static_cast<Reader*>(closure);
    if (r->pos + length > r->data->size()) return CAIRO_STATUS_READ_ERROR;
    std::memcpy(out, r->data->data() + r->pos, length);
    r->pos += length;
    return CAIRO_STATUS_SUCCESS;
  };
  Decoded d;
  d.surface.reset(cairo_image_surface_create_from_png_stream(read, &reader));
  EXPECT_EQ(cairo_surface_status(d.surface.get()), CAIRO_STATUS_SUCCESS);
  cairo_surface_flush(d.surface.get());
  d.width = cairo_image_surface_get_width(d.surface.get());
  d.height = cairo_image_surface_get_height(d.surface.get());
  return d;
}

bool same(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }
std::string str(Rgb c) {
  return "(" + std::to_string(c.r) + "," + std::to_string(c.g) + "," + std::to_string(c.b) + ")";
}

TEST(RenderPng, IsACompressedPictureOfTheLayoutsSize) {
  RenderOptions o;
  o.pixels_per_m = 10;
  o.margin_m = 1;
  o.legend = false;
  const auto png = to_png(square_with_hole(), {}, o);
  const std::uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(std::memcmp(png.data(), signature, 8), 0);
  const Decoded d = decode(png);
  EXPECT_EQ(d.width, 120);
  EXPECT_EQ(d.height, 120);
  // deflate, not stored blocks: far below the 120 x 120 x 3 raw bytes
  EXPECT_LT(png.size(), 120u * 120u * 3u / 5u) << png.size() << " bytes";
}

TEST(RenderPng, ColoursFreeSpaceHolesObstaclesFrontiersAndPath) {
  RenderOptions o;
  o.pixels_per_m = 10;
  o.margin_m = 1;
  o.legend = false;
  const Path path{{2, 2}, {8, 2}, {8, 8}};
  const auto map = square_with_hole();
  const Layout l = layout_of(map, path, o);
  const Decoded d = decode(to_png(map, path, o));
  auto at = [&](double x_m, double y_m) {
    const auto [px, py] = l.to_pixel(x_m, y_m);
    return d.at(px, py);
  };
  EXPECT_TRUE(same(at(2, 6), kFree)) << str(at(2, 6));
  EXPECT_TRUE(same(at(5, 5), kBackground)) << "the hole: " << str(at(5, 5));
  EXPECT_TRUE(same(at(-0.5, 5), kBackground)) << "outside: " << str(at(-0.5, 5));
  EXPECT_TRUE(same(at(0, 5), kObstacle)) << "the left wall: " << str(at(0, 5));
  EXPECT_TRUE(same(at(4, 5), kObstacle)) << "the hole's rim: " << str(at(4, 5));
  EXPECT_TRUE(same(at(5, 10), kFrontier)) << "the top side: " << str(at(5, 10));
  EXPECT_TRUE(same(at(5, 2), kPath)) << "the path: " << str(at(5, 2));
  EXPECT_TRUE(same(at(2, 2), kStart)) << "the start: " << str(at(2, 2));
}

TEST(RenderPng, IsAntialiased) {
  // A wall at 30 degrees: antialiased, its pixels take many shades between black and
  // white (a jagged line would have two).
  RenderOptions o;
  o.legend = false;
  const Decoded d = decode(to_png(turned(square_with_hole(), kPi / 6), {}, o));
  std::set<int> greys;
  for (int y = 0; y < d.height; ++y)
    for (int x = 0; x < d.width; ++x) {
      const Rgb c = d.at(x, y);
      if (c.r == c.g && c.g == c.b && c.r > 0 && c.r < 200) greys.insert(c.r);
    }
  EXPECT_GT(greys.size(), 20u);
}

TEST(RenderPng, FooterHasLegendAndScaleBar) {
  RenderOptions o;
  o.pixels_per_m = 10;
  const auto map = square_with_hole();
  const Layout l = layout_of(map, {}, o);
  EXPECT_GE(l.width, 500);   // widened for the legend
  EXPECT_EQ(l.height, l.map_height + 30);
  const Decoded d = decode(to_png(map, {}, o));
  ASSERT_EQ(d.height, l.height);
  // the footer holds the legend's swatches (orange, blue) and black text and bar
  int orange = 0, blue = 0, black = 0;
  for (int y = l.map_height; y < d.height; ++y)
    for (int x = 0; x < d.width; ++x) {
      const Rgb c = d.at(x, y);
      orange += same(c, kFrontier);
      blue += same(c, kPath);
      black += same(c, kObstacle);
    }
  EXPECT_GT(orange, 10);
  EXPECT_GT(blue, 10);
  EXPECT_GT(black, 200);
  // the scale bar: a black run at the right, 1, 2 or 5 times a power of ten in metres
  const int mid = l.map_height + 15;
  int run = 0, best = 0;
  for (int x = 0; x < d.width; ++x) {
    run = same(d.at(x, mid), kObstacle) ? run + 1 : 0;
    best = std::max(best, run);
  }
  const double metres = best / l.scale;
  const double mantissa = metres / std::pow(10.0, std::floor(std::log10(metres)));
  EXPECT_TRUE(std::abs(mantissa - 1) < 0.1 || std::abs(mantissa - 2) < 0.2 || std::abs(mantissa - 5) < 0.5)
      << best << " px = " << metres << " m";
}

TEST(RenderAlign, FindsTheWallDirectionAndTurnsTheMapOntoTheAxes) {
  const auto map = turned(square_with_hole(), 0.5);  // 28.6 degrees
  EXPECT_NEAR(dominant_wall_angle(map), 0.5, 1e-9);
  EXPECT_NEAR(dominant_wall_angle(turned(square_with_hole(), -0.3)), -0.3, 1e-9);
  EXPECT_NEAR(dominant_wall_angle(turned(square_with_hole(), 1.2)), 1.2 - kPi / 2, 1e-9);  // modulo 90 degrees
  RenderOptions o;
  o.pixels_per_m = 10;
  o.margin_m = 1;
  o.legend = false;
  const Layout turned_layout = layout_of(map, {}, o);
  EXPECT_GT(turned_layout.width, 140);  // the turned square's bounding box
  o.align = true;
  const Layout aligned = layout_of(map, {}, o);
  EXPECT_NEAR(aligned.rotation_rad, -0.5, 1e-9);
  EXPECT_EQ(aligned.width, 120);
  EXPECT_EQ(aligned.height, 120);
  // aligned, the left wall is a vertical black line again
  const Decoded d = decode(to_png(map, {}, o));
  for (double y_m : {2.0, 5.0, 8.0}) {
    const auto [x, y] = aligned.to_pixel(std::cos(0.5) * 0 - std::sin(0.5) * y_m, std::sin(0.5) * 0 + std::cos(0.5) * y_m);
    EXPECT_NEAR(x, 10.0, 1e-6);
    EXPECT_TRUE(same(d.at(x, y), kObstacle)) << str(d.at(x, y));
  }
}

TEST(RenderSvg, DrawsTheSamePictureAsVectors) {
  RenderOptions o;
  o.pixels_per_m = 10;
  const auto map = square_with_hole();
  const Layout l = layout_of(map, {{1, 1}, {2, 2}}, o);
  const auto svg = to_svg(map, {{1, 1}, {2, 2}}, o);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("width=\"" + std::to_string(l.width) + "px\""), std::string::npos) << svg.substr(0, 300);
  EXPECT_NE(svg.find("height=\"" + std::to_string(l.height) + "px\""), std::string::npos);
  EXPECT_NE(svg.find("fill-rule:evenodd"), std::string::npos);
  EXPECT_NE(svg.find("stroke:rgb(0%,0%,0%)"), std::string::npos);                 // obstacles
  EXPECT_NE(svg.find("stroke:rgb(100%,54.901961%,0%)"), std::string::npos);      // frontiers
  EXPECT_NE(svg.find("stroke:rgb(11.764706%,35.294118%,86.27451%)"), std::string::npos);  // the path
  EXPECT_EQ(svg.find("<image"), std::string::npos);  // vectors, no embedded picture
}

TEST(RenderEncodePng, WritesAReadyPicture) {
  Image img;
  img.width = 300;
  img.height = 200;
  img.rgb.assign(300 * 200 * 3, 7);
  img.rgb[3 * (10 * 300 + 20)] = 255;  // one red pixel at (20, 10)
  const auto png = encode_png(img);
  EXPECT_LT(png.size(), 2000u);
  const Decoded d = decode(png);
  EXPECT_EQ(d.width, 300);
  EXPECT_EQ(d.height, 200);
  EXPECT_TRUE(same(d.at(20, 10), {255, 7, 7})) << str(d.at(20, 10));
  EXPECT_TRUE(same(d.at(21, 10), {7, 7, 7}));
}

// cairo's and fontconfig's caches (the legend's text) freed at the end, so the
// sanitizer build's leak check sees only what the tests leave.
class FreeFontCaches : public testing::Environment {
 public:
  void TearDown() override {
    cairo_debug_reset_static_data();
    FcFini();
  }
};
const auto* const kFreeFontCaches = testing::AddGlobalTestEnvironment(new FreeFontCaches);

}  // namespace
}  // namespace pex::render_map
