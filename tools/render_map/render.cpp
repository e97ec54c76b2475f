#include "render.hpp"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

namespace pex::render_map {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kFooterPx = 30;      // legend and scale bar, below the map
constexpr int kMinLegendWidth = 560;  // the legend's entries and the scale bar side by side

struct Rotation {
  double c = 1, s = 0;
  explicit Rotation(double rad) : c(std::cos(rad)), s(std::sin(rad)) {}
  std::pair<double, double> operator()(double x, double y) const { return {c * x - s * y, s * x + c * y}; }
};

void set_colour(cairo_t* cr, Rgb c, double alpha = 1.0) {
  cairo_set_source_rgba(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0, alpha);
}

// 1, 2 or 5 times a power of ten, at most `at_most` m.
double nice_length(double at_most) {
  if (!(at_most > 0)) return 1;
  const double p = std::pow(10.0, std::floor(std::log10(at_most)));
  for (double m : {5.0, 2.0, 1.0})
    if (m * p <= at_most) return m * p;
  return p;
}

void draw_footer(cairo_t* cr, const Layout& l, bool rotated) {
  const double top = l.map_height;
  set_colour(cr, kFooter);
  cairo_rectangle(cr, 0, top, l.width, kFooterPx);
  cairo_fill(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 12);
  const double mid = top + kFooterPx / 2.0;
  double x = 8;
  auto label = [&](const char* text) {
    set_colour(cr, {0, 0, 0});
    cairo_move_to(cr, x, mid + 4);
    cairo_show_text(cr, text);
    cairo_text_extents_t e;
    cairo_text_extents(cr, text, &e);
    x += e.x_advance + 14;
  };
  // free space: a white box with a grey rim
  set_colour(cr, kFree);
  cairo_rectangle(cr, x, mid - 6, 16, 12);
  cairo_fill_preserve(cr);
  set_colour(cr, kBackground);
  cairo_set_line_width(cr, 1);
  cairo_stroke(cr);
  x += 20;
  label("free");
  auto line_entry = [&](Rgb c, double width, const char* text) {
    set_colour(cr, c);
    cairo_set_line_width(cr, width);
    cairo_move_to(cr, x, mid);
    cairo_line_to(cr, x + 18, mid);
    cairo_stroke(cr);
    x += 22;
    label(text);
  };
  line_entry(kObstacle, 2, "obstacle");
  line_entry(kFrontier, 2, "frontier");
  line_entry(kPath, 2, "robot path");
  set_colour(cr, kStart);
  cairo_arc(cr, x + 5, mid, 4, 0, 2 * kPi);
  cairo_fill(cr);
  x += 14;
  label("start");
  if (rotated) {
    char text[48];
    std::snprintf(text, sizeof text, "rotated %.1f deg", l.rotation_rad * 180 / kPi);
    label(text);
  }
  // scale bar at the right: about a fifth of the width
  const double bar_m = nice_length(l.width / 5.0 / l.scale);
  const double bar_px = bar_m * l.scale;
  char text[32];
  if (bar_m >= 1) std::snprintf(text, sizeof text, "%g m", bar_m);
  else std::snprintf(text, sizeof text, "%g cm", bar_m * 100);
  cairo_text_extents_t e;
  cairo_text_extents(cr, text, &e);
  const double right = l.width - 8;
  const double bar_left = right - e.x_advance - 8 - bar_px;
  set_colour(cr, {0, 0, 0});
  cairo_rectangle(cr, bar_left, mid - 2, bar_px, 4);
  cairo_fill(cr);
  cairo_set_line_width(cr, 1);
  for (double tick : {bar_left, bar_left + bar_px}) {
    cairo_move_to(cr, tick, mid - 6);
    cairo_line_to(cr, tick, mid + 6);
  }
  cairo_stroke(cr);
  cairo_move_to(cr, right - e.x_advance, mid + 4);
  cairo_show_text(cr, text);
}

// The one drawing of both outputs, in pixels.
void draw(cairo_t* cr, const pex::polygon_map_t& map, const Path& path, const Layout& l, const RenderOptions& o) {
  const Rotation rot(l.rotation_rad);
  auto px = [&](double x, double y) {
    const auto [rx, ry] = rot(x, y);
    return std::pair<double, double>{(rx - l.min_x) * l.scale, (l.max_y - ry) * l.scale};
  };
  set_colour(cr, kBackground);
  cairo_paint(cr);
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_GOOD);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  // Free space: all rings in one path, even-odd, so holes stay unfilled.
  for (const auto& r : map.rings) {
    const std::size_t n = std::min(r.x.size(), r.y.size());
    for (std::size_t i = 0; i < n; ++i) {
      const auto [x, y] = px(r.x[i], r.y[i]);
      if (i == 0) cairo_move_to(cr, x, y);
      else cairo_line_to(cr, x, y);
    }
    if (n) cairo_close_path(cr);
  }
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
  set_colour(cr, kFree);
  // Not antialiased: every edge of the fill is drawn over by its obstacle or frontier
  // line, and grey steps under them would only make the PNG larger.
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_NONE);
  cairo_fill(cr);
  cairo_set_antialias(cr, CAIRO_ANTIALIAS_GOOD);
  // Frontier edges first, obstacles over them.
  for (const bool obstacles : {false, true}) {
    for (const auto& r : map.rings) {
      const std::size_t n = std::min({r.x.size(), r.y.size(), r.edge_type.size()});
      for (std::size_t i = 0; i < n; ++i) {
        if ((r.edge_type[i] == pex::polygon_ring_t::EDGE_OBSTACLE) != obstacles) continue;
        const std::size_t j = (i + 1) % n;
        const auto [x0, y0] = px(r.x[i], r.y[i]);
        const auto [x1, y1] = px(r.x[j], r.y[j]);
        cairo_move_to(cr, x0, y0);
        cairo_line_to(cr, x1, y1);
      }
    }
    set_colour(cr, obstacles ? kObstacle : kFrontier);
    cairo_set_line_width(cr, 2.0);
    cairo_stroke(cr);
  }
  if (!path.empty()) {
    for (std::size_t k = 0; k < path.size(); ++k) {
      const auto [x, y] = px(path[k].first, path[k].second);
      if (k == 0) cairo_move_to(cr, x, y);
      else cairo_line_to(cr, x, y);
    }
    set_colour(cr, kPath);
    cairo_set_line_width(cr, 2.0);
    cairo_stroke(cr);
    const auto [sx, sy] = px(path.front().first, path.front().second);
    set_colour(cr, kStart);
    cairo_arc(cr, sx, sy, 4, 0, 2 * kPi);
    cairo_fill(cr);
    const auto [ex, ey] = px(path.back().first, path.back().second);
    set_colour(cr, kPath);
    cairo_arc(cr, ex, ey, 4, 0, 2 * kPi);
    cairo_fill(cr);
  }
  if (o.legend) draw_footer(cr, l, o.align);
}

using Surface = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using Context = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

cairo_status_t append(void* closure, const unsigned char* data, unsigned int length) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(closure);
  out->insert(out->end(), data, data + length);
  return CAIRO_STATUS_SUCCESS;
}

std::vector<std::uint8_t> png_of(cairo_surface_t* surface) {
  std::vector<std::uint8_t> png;
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface, append, &png);
  if (status != CAIRO_STATUS_SUCCESS) throw std::runtime_error(std::string("PNG: ") + cairo_status_to_string(status));
  return png;
}

Surface image_surface(int width, int height) {
  Surface s(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height), cairo_surface_destroy);
  if (cairo_surface_status(s.get()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("a " + std::to_string(width) + " x " + std::to_string(height) + " picture: " +
                             cairo_status_to_string(cairo_surface_status(s.get())));
  return s;
}

}  // namespace

double dominant_wall_angle(const pex::polygon_map_t& map) {
  // Directions modulo 90 degrees as angles times 4 on the circle, weighted by length.
  double c = 0, s = 0;
  for (const auto& r : map.rings) {
    const std::size_t n = std::min({r.x.size(), r.y.size(), r.edge_type.size()});
    for (std::size_t i = 0; i < n; ++i) {
      if (r.edge_type[i] != pex::polygon_ring_t::EDGE_OBSTACLE) continue;
      const std::size_t j = (i + 1) % n;
      const double dx = r.x[j] - r.x[i], dy = r.y[j] - r.y[i];
      const double length = std::hypot(dx, dy);
      if (!std::isfinite(length) || length <= 0) continue;
      const double a = 4 * std::atan2(dy, dx);
      c += length * std::cos(a);
      s += length * std::sin(a);
    }
  }
  if (std::hypot(c, s) < 1e-12) return 0.0;
  double angle = std::atan2(s, c) / 4;  // (-pi/4, pi/4]
  if (angle <= -kPi / 4) angle += kPi / 2;
  return angle;
}

std::pair<double, double> Layout::to_pixel(double x_m, double y_m) const {
  const auto [rx, ry] = Rotation(rotation_rad)(x_m, y_m);
  return {(rx - min_x) * scale, (max_y - ry) * scale};
}

Layout layout_of(const pex::polygon_map_t& map, const Path& path, const RenderOptions& o) {
  Layout l;
  l.rotation_rad = o.align ? -dominant_wall_angle(map) : 0.0;
  const Rotation rot(l.rotation_rad);
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
  auto grow = [&](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    const auto [rx, ry] = rot(x, y);
    lo_x = std::min(lo_x, rx), hi_x = std::max(hi_x, rx), lo_y = std::min(lo_y, ry), hi_y = std::max(hi_y, ry);
  };
  for (const auto& r : map.rings)
    for (std::size_t i = 0; i < r.x.size() && i < r.y.size(); ++i) grow(r.x[i], r.y[i]);
  for (const auto& p : path) grow(p.first, p.second);
  if (!std::isfinite(lo_x)) lo_x = lo_y = 0, hi_x = hi_y = 1;
  lo_x -= o.margin_m, lo_y -= o.margin_m, hi_x += o.margin_m, hi_y += o.margin_m;
  const double span = std::max(hi_x - lo_x, hi_y - lo_y);
  l.scale = std::min(o.pixels_per_m, o.max_side_px / span);
  l.min_x = lo_x;
  l.max_y = hi_y;
  // (less a hair: a turned map's 120.0000001 px is 120)
  l.width = std::max(1, static_cast<int>(std::ceil((hi_x - lo_x) * l.scale - 1e-6)));
  l.map_height = std::max(1, static_cast<int>(std::ceil((hi_y - lo_y) * l.scale - 1e-6)));
  l.height = l.map_height;
  if (o.legend) {
    // the map centred in a picture wide enough for the legend
    if (l.width < kMinLegendWidth) {
      l.min_x -= (kMinLegendWidth - l.width) / 2.0 / l.scale;
      l.width = kMinLegendWidth;
    }
    l.height += kFooterPx;
  }
  return l;
}

std::string to_svg(const pex::polygon_map_t& map, const Path& path, const RenderOptions& o) {
  const Layout l = layout_of(map, path, o);
  std::vector<std::uint8_t> text;
  {
    Surface surface(cairo_svg_surface_create_for_stream(append, &text, l.width, l.height), cairo_surface_destroy);
    cairo_svg_surface_set_document_unit(surface.get(), CAIRO_SVG_UNIT_PX);
    Context cr(cairo_create(surface.get()), cairo_destroy);
    draw(cr.get(), map, path, l, o);
    cr.reset();
    cairo_surface_finish(surface.get());
    if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS)
      throw std::runtime_error(std::string("SVG: ") + cairo_status_to_string(cairo_surface_status(surface.get())));
  }
  return {text.begin(), text.end()};
}

std::vector<std::uint8_t> to_png(const pex::polygon_map_t& map, const Path& path, const RenderOptions& o) {
  const Layout l = layout_of(map, path, o);
  Surface surface = image_surface(l.width, l.height);
  {
    Context cr(cairo_create(surface.get()), cairo_destroy);
    draw(cr.get(), map, path, l, o);
  }
  return png_of(surface.get());
}

std::vector<std::uint8_t> encode_png(const Image& image) {
  Surface surface = image_surface(image.width, image.height);
  cairo_surface_flush(surface.get());
  unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  for (int y = 0; y < image.height; ++y) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::size_t>(y) * stride);
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = &image.rgb[3 * (static_cast<std::size_t>(y) * image.width + x)];
      row[x] = (std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | p[2];  // cairo's RGB24: native 0xXXRRGGBB
    }
  }
  cairo_surface_mark_dirty(surface.get());
  return png_of(surface.get());
}

}  // namespace pex::render_map
