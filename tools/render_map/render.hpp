#pragma once
// Drawing a MAP message with cairo (Debian's libcairo2): one drawing for SVG and PNG —
// free space filled (even-odd, so holes stay empty), obstacle edges black, frontier
// edges orange, the robot's path blue with its start and last position, and a footer
// with the legend and a scale bar. Antialiased; the PNG is libpng's compressed one.
// encode_png writes a ready RGB picture (pex-make-world's grid) the same way.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <pex/polygon_map_t.hpp>

namespace pex::render_map {

struct RenderOptions {
  double pixels_per_m = 20.0;
  double margin_m = 1.0;
  int max_side_px = 8000;  // the scale shrinks for larger maps
  bool align = false;      // rotate the map frame so its dominant wall direction lies along the axes
  bool legend = true;      // the footer: legend and scale bar
};

using Path = std::vector<std::pair<double, double>>;  // robot positions, m

// The map's dominant wall direction, rad in (-pi/4, pi/4]: the length-weighted mean of
// the obstacle edges' directions modulo 90 degrees (walls meet at right angles), 0 with
// no obstacle edge. --align rotates the map by minus this angle.
double dominant_wall_angle(const pex::polygon_map_t& map);

// Colours, 0-255 RGB: what the tests look for in the pictures.
struct Rgb {
  std::uint8_t r, g, b;
};
inline constexpr Rgb kBackground{200, 200, 200};  // unknown / outside the map
inline constexpr Rgb kFree{255, 255, 255};
inline constexpr Rgb kObstacle{0, 0, 0};
inline constexpr Rgb kFrontier{255, 140, 0};
inline constexpr Rgb kPath{30, 90, 220};
inline constexpr Rgb kStart{0, 160, 0};
inline constexpr Rgb kFooter{245, 245, 245};

// Where the map lies in the picture, for callers and tests.
struct Layout {
  int width = 1, height = 1;  // the whole picture, px
  int map_height = 1;         // the map's part (the footer is below it)
  double scale = 20.0;        // px per m
  double rotation_rad = 0.0;  // the map was rotated by this (--align: minus the wall angle)
  double min_x = 0, max_y = 0;  // the (rotated) world point at the picture's top left corner, m
  std::pair<double, double> to_pixel(double x_m, double y_m) const;
};

Layout layout_of(const pex::polygon_map_t& map, const Path& path, const RenderOptions& options);

std::string to_svg(const pex::polygon_map_t& map, const Path& path, const RenderOptions& options);
std::vector<std::uint8_t> to_png(const pex::polygon_map_t& map, const Path& path, const RenderOptions& options);

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes a pixel, top row first
};
// A ready picture as PNG, with the same writer (cairo).
std::vector<std::uint8_t> encode_png(const Image& image);

}  // namespace pex::render_map
