#include "render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

namespace pex::render_map {

namespace {

struct Frame {
  double min_x = 0, min_y = 0, max_x = 1, max_y = 1;
  double scale = 20.0;  // px per m
  int width = 1, height = 1;
  double px(double x) const { return (x - min_x) * scale; }
  double py(double y) const { return (max_y - y) * scale; }  // y up in the world, down in images
};

Frame frame_of(const pex::polygon_map_t& map, const Path& path, const RenderOptions& o) {
  Frame f;
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
  auto grow = [&](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x), lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
  };
  for (const auto& r : map.rings)
    for (std::size_t i = 0; i < r.x.size() && i < r.y.size(); ++i) grow(r.x[i], r.y[i]);
  for (const auto& p : path) grow(p.first, p.second);
  if (!std::isfinite(lo_x)) lo_x = lo_y = 0, hi_x = hi_y = 1;
  f.min_x = lo_x - o.margin_m, f.min_y = lo_y - o.margin_m;
  f.max_x = hi_x + o.margin_m, f.max_y = hi_y + o.margin_m;
  const double span = std::max(f.max_x - f.min_x, f.max_y - f.min_y);
  f.scale = std::min(o.pixels_per_m, o.max_side_px / span);
  f.width = std::max(1, static_cast<int>(std::ceil((f.max_x - f.min_x) * f.scale)));
  f.height = std::max(1, static_cast<int>(std::ceil((f.max_y - f.min_y) * f.scale)));
  return f;
}

constexpr std::array<std::uint8_t, 3> kBackground{200, 200, 200};
constexpr std::array<std::uint8_t, 3> kFree{255, 255, 255};
constexpr std::array<std::uint8_t, 3> kObstacle{0, 0, 0};
constexpr std::array<std::uint8_t, 3> kFrontier{255, 140, 0};
constexpr std::array<std::uint8_t, 3> kPath{30, 90, 220};

void draw_line(Image& img, double x0, double y0, double x1, double y1, const std::array<std::uint8_t, 3>& c,
               int thickness) {
  const double length = std::hypot(x1 - x0, y1 - y0);
  const int steps = std::max(1, static_cast<int>(std::ceil(length * 2)));
  const int half = thickness / 2;
  for (int s = 0; s <= steps; ++s) {
    const double t = static_cast<double>(s) / steps;
    const int x = static_cast<int>(std::floor(x0 + t * (x1 - x0)));
    const int y = static_cast<int>(std::floor(y0 + t * (y1 - y0)));
    for (int dy = -half; dy <= half; ++dy)
      for (int dx = -half; dx <= half; ++dx) img.set(x + dx, y + dy, c[0], c[1], c[2]);
  }
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 24));
  out.push_back(static_cast<std::uint8_t>(v >> 16));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v));
}

void put_chunk(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  put_u32(out, crc32(out.data() + start, out.size() - start));
}

}  // namespace

void Image::set(int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  auto* p = &rgb[3 * (static_cast<std::size_t>(y) * width + x)];
  p[0] = r, p[1] = g, p[2] = b;
}

std::string to_svg(const pex::polygon_map_t& map, const Path& path, const RenderOptions& o) {
  const Frame f = frame_of(map, path, o);
  std::string svg;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\">\n",
                f.width, f.height, f.width, f.height);
  svg += buf;
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"rgb(200,200,200)\"/>\n";
  // Free space: one path of all rings, even-odd, so holes stay unfilled.
  svg += "<path fill=\"white\" fill-rule=\"evenodd\" stroke=\"none\" d=\"";
  for (const auto& r : map.rings) {
    const std::size_t n = std::min(r.x.size(), r.y.size());
    for (std::size_t i = 0; i < n; ++i) {
      std::snprintf(buf, sizeof buf, "%c%.2f %.2f ", i == 0 ? 'M' : 'L', f.px(r.x[i]), f.py(r.y[i]));
      svg += buf;
    }
    if (n) svg += "Z ";
  }
  svg += "\"/>\n";
  for (const auto& r : map.rings) {
    const std::size_t n = std::min({r.x.size(), r.y.size(), r.edge_type.size()});
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      const bool obstacle = r.edge_type[i] == pex::polygon_ring_t::EDGE_OBSTACLE;
      std::snprintf(buf, sizeof buf,
                    "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"%s\" stroke-width=\"%s\"/>\n",
                    f.px(r.x[i]), f.py(r.y[i]), f.px(r.x[j]), f.py(r.y[j]),
                    obstacle ? "black" : "rgb(255,140,0)", obstacle ? "2" : "1.5");
      svg += buf;
    }
  }
  if (path.size() > 1) {
    svg += "<polyline fill=\"none\" stroke=\"rgb(30,90,220)\" stroke-width=\"1.5\" points=\"";
    for (const auto& p : path) {
      std::snprintf(buf, sizeof buf, "%.2f,%.2f ", f.px(p.first), f.py(p.second));
      svg += buf;
    }
    svg += "\"/>\n";
  }
  svg += "</svg>\n";
  return svg;
}

Image rasterise(const pex::polygon_map_t& map, const Path& path, const RenderOptions& o) {
  const Frame f = frame_of(map, path, o);
  Image img;
  img.width = f.width;
  img.height = f.height;
  img.rgb.resize(static_cast<std::size_t>(f.width) * f.height * 3);
  for (std::size_t i = 0; i < img.rgb.size(); i += 3)
    img.rgb[i] = kBackground[0], img.rgb[i + 1] = kBackground[1], img.rgb[i + 2] = kBackground[2];
  // Scanline fill, even-odd over every ring (holes stay background).
  std::vector<double> xs;
  for (int row = 0; row < f.height; ++row) {
    const double y = row + 0.5;
    xs.clear();
    for (const auto& r : map.rings) {
      const std::size_t n = std::min(r.x.size(), r.y.size());
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t j = (i + 1) % n;
        const double y0 = f.py(r.y[i]), y1 = f.py(r.y[j]);
        if ((y0 <= y) == (y1 <= y)) continue;  // half-open rule: no double count at vertices
        const double x0 = f.px(r.x[i]), x1 = f.px(r.x[j]);
        xs.push_back(x0 + (y - y0) / (y1 - y0) * (x1 - x0));
      }
    }
    std::sort(xs.begin(), xs.end());
    for (std::size_t k = 0; k + 1 < xs.size(); k += 2) {
      const int from = std::max(0, static_cast<int>(std::ceil(xs[k] - 0.5)));
      const int to = std::min(f.width - 1, static_cast<int>(std::floor(xs[k + 1] - 0.5)));
      for (int x = from; x <= to; ++x) img.set(x, row, kFree[0], kFree[1], kFree[2]);
    }
  }
  // Frontier edges first, obstacles over them.
  for (const bool obstacles : {false, true}) {
    for (const auto& r : map.rings) {
      const std::size_t n = std::min({r.x.size(), r.y.size(), r.edge_type.size()});
      for (std::size_t i = 0; i < n; ++i) {
        const bool is_obstacle = r.edge_type[i] == pex::polygon_ring_t::EDGE_OBSTACLE;
        if (is_obstacle != obstacles) continue;
        const std::size_t j = (i + 1) % n;
        draw_line(img, f.px(r.x[i]), f.py(r.y[i]), f.px(r.x[j]), f.py(r.y[j]),
                  obstacles ? kObstacle : kFrontier, obstacles ? 2 : 1);
      }
    }
  }
  for (std::size_t k = 1; k < path.size(); ++k)
    draw_line(img, f.px(path[k - 1].first), f.py(path[k - 1].second), f.px(path[k].first),
              f.py(path[k].second), kPath, 1);
  return img;
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc) {
  static const auto table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::uint32_t adler32(const std::uint8_t* data, std::size_t size) {
  std::uint32_t a = 1, b = 0;
  for (std::size_t i = 0; i < size; ++i) {
    a = (a + data[i]) % 65521;
    b = (b + a) % 65521;
  }
  return (b << 16) | a;
}

std::vector<std::uint8_t> encode_png(const Image& image) {
  std::vector<std::uint8_t> out{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<std::uint8_t> ihdr;
  put_u32(ihdr, static_cast<std::uint32_t>(image.width));
  put_u32(ihdr, static_cast<std::uint32_t>(image.height));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // 8 bit, RGB, deflate, adaptive filters, no interlace
  put_chunk(out, "IHDR", ihdr);
  // Raw scanlines, each with filter type 0.
  std::vector<std::uint8_t> raw;
  const std::size_t row_bytes = static_cast<std::size_t>(image.width) * 3;
  raw.reserve((row_bytes + 1) * image.height);
  for (int y = 0; y < image.height; ++y) {
    raw.push_back(0);
    raw.insert(raw.end(), image.rgb.begin() + y * row_bytes, image.rgb.begin() + (y + 1) * row_bytes);
  }
  // zlib stream of stored (uncompressed) deflate blocks of at most 65535 bytes.
  std::vector<std::uint8_t> z{0x78, 0x01};
  std::size_t pos = 0;
  do {
    const std::size_t len = std::min<std::size_t>(65535, raw.size() - pos);
    const bool last = pos + len == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<std::uint8_t>(len & 0xFF));
    z.push_back(static_cast<std::uint8_t>(len >> 8));
    z.push_back(static_cast<std::uint8_t>(~len & 0xFF));
    z.push_back(static_cast<std::uint8_t>((~len >> 8) & 0xFF));
    z.insert(z.end(), raw.begin() + pos, raw.begin() + pos + len);
    pos += len;
  } while (pos < raw.size());
  put_u32(z, adler32(raw.data(), raw.size()));
  put_chunk(out, "IDAT", z);
  put_chunk(out, "IEND", {});
  return out;
}

}  // namespace pex::render_map
