// pex-render-map --log IN.lcm [--channel MAP] --svg OUT.svg --png OUT.png
// pex-render-map --map IN.geojson --svg OUT.svg --png OUT.png
// Draws the last MAP message of an LCM log, or a saved map file (pex-map save), with
// cairo: free space filled, obstacle edges black, frontier edges orange, the robot
// path from every MAP's pose (a map file: its one pose), legend and scale bar;
// --align turns the map so its dominant wall direction lies along the picture's axes.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <CLI/CLI.hpp>
#include <pex/polygon_map_t.hpp>

#include "cli/command_line.hpp"
#include "map_source.hpp"
#include "render.hpp"
#include "runtime/channels.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Render the last MAP of an LCM log, or a saved map file, to SVG and/or PNG"};
  std::string log_path, map_path, channel{pex::runtime::channels::kMap}, svg_path, png_path;
  pex::render_map::RenderOptions options;
  auto* log_option = app.add_option("--log", log_path, "LCM log to read");
  app.add_option("--map", map_path, "saved map file to read (GeoJSON, from pex-map save)")->excludes(log_option);
  app.add_option("--channel", channel, "channel of the pex.polygon_map_t messages");
  app.add_option("--svg", svg_path, "SVG output");
  app.add_option("--png", png_path, "PNG output");
  app.add_option("--pixels-per-m", options.pixels_per_m, "scale (shrinks for large maps)")->check(CLI::PositiveNumber);
  app.add_flag("--align", options.align, "rotate the map so its dominant wall direction lies along the axes");
  bool no_legend = false;
  app.add_flag("--no-legend", no_legend, "no footer (legend, scale bar)");
  if (const auto code = pex::cli::parse_command_line(app, "pex-render-map", argc, argv)) return *code;
  options.legend = !no_legend;
  if (svg_path.empty() && png_path.empty()) {
    std::fprintf(stderr, "pex-render-map: give --svg and/or --png\n");
    return EX_USAGE;
  }
  if (log_path.empty() == map_path.empty()) {
    std::fprintf(stderr, "pex-render-map: give --log or --map\n");
    return EX_USAGE;
  }
  // An output that cannot be written (no such folder, full disk) is exit 73, never "rendered";
  // a folder that is not there or not writable is found before the log is read.
  const auto cannot_write = [](const std::string& path) {
    std::fprintf(stderr, "pex-render-map: cannot write %s\n", path.c_str());
    return EX_CANTCREAT;
  };
  for (const std::string& out : {svg_path, png_path}) {
    if (out.empty()) continue;
    const std::filesystem::path folder = std::filesystem::path(out).parent_path();
    if (::access(folder.empty() ? "." : folder.c_str(), W_OK) != 0) return cannot_write(out);
  }
  pex::map_files::LogMaps maps;
  if (int rc = pex::map_files::load_map("pex-render-map", map_path, log_path, channel, maps); rc != 0) return rc;
  const pex::polygon_map_t& last = *maps.last;
  const pex::render_map::Path& path = maps.robot_path;
  const long rejected = maps.rejected;
  std::string svg;
  std::vector<std::uint8_t> png;
  try {
    if (!svg_path.empty()) svg = pex::render_map::to_svg(last, path, options);
    if (!png_path.empty()) png = pex::render_map::to_png(last, path, options);
  } catch (const std::exception& e) {  // cairo: a picture too large for memory
    std::fprintf(stderr, "pex-render-map: %s\n", e.what());
    return cannot_write(png_path.empty() ? svg_path : png_path);
  }
  if (!svg_path.empty()) {
    std::ofstream out(svg_path);
    out << svg;
    out.close();
    if (!out) return cannot_write(svg_path);
  }
  if (!png_path.empty()) {
    std::ofstream out(png_path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    out.close();
    if (!out) return cannot_write(png_path);
  }
  const pex::render_map::Layout layout = pex::render_map::layout_of(last, path, options);
  std::printf("rendered %d rings, %d vertices, %.1f m2 free, %zu path points (%ld messages rejected)\n",
              last.nrings, last.vertex_count, last.free_area_m2, path.size(), rejected);
  std::printf("picture %d x %d px, %.2f px/m, rotated %.1f deg", layout.width, layout.height, layout.scale,
              layout.rotation_rad * 180 / 3.14159265358979323846);
  if (!svg_path.empty()) std::printf("; SVG %zu bytes", svg.size());
  if (!png_path.empty()) std::printf("; PNG %zu bytes", png.size());
  std::printf("\n");
  return 0;
}
