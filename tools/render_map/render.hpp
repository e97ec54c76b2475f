#pragma once
// Drawing a MAP message: SVG text, and a small RGB rasteriser (scanline fill,
// line drawing) with a minimal PNG writer (zlib stored blocks, CRC-32,
// Adler-32), so rendering needs no image library.
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
};

using Path = std::vector<std::pair<double, double>>;  // robot positions, m

// SVG with free space filled (even-odd, so holes stay empty), obstacle edges
// in black, frontier edges in orange, the robot path in blue.
std::string to_svg(const pex::polygon_map_t& map, const Path& path, const RenderOptions& options);

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes a pixel, top row first
  void set(int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b);
  const std::uint8_t* at(int x, int y) const { return &rgb[3 * (static_cast<std::size_t>(y) * width + x)]; }
};

// The same picture as to_svg, rasterised.
Image rasterise(const pex::polygon_map_t& map, const Path& path, const RenderOptions& options);

// PNG (8-bit RGB, no compression) of an image.
std::vector<std::uint8_t> encode_png(const Image& image);

std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);
std::uint32_t adler32(const std::uint8_t* data, std::size_t size);

}  // namespace pex::render_map
