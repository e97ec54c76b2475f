// pex-make-world --log IN.clf --poses POSES.txt --out WORLD.wkt [--svg F] [--png F]:
// a simulator world from a real building. The log's laser scans, each at its
// pose from POSES.txt (`t x y theta` per scan, as `pex-slam --poses` writes;
// matched by time stamp), are ray-traced into an occupancy grid; the free
// space connected to the trajectory becomes the world's free space and its
// boundary the walls (make_world.hpp says how and why).
#include <CLI/CLI.hpp>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/command_line.hpp"
#include "evaluation/carmen_log.hpp"
#include "evaluation/relations.hpp"
#include "make_world.hpp"
#include "render.hpp"

namespace mw = pex::make_world;
namespace ev = pex::evaluation;

namespace {

std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A simulator world (WKT walls) from a CARMEN log and the poses of its scans"};
  std::string log_path, poses_path, out_path, svg_path, png_path, title = "a world made from real laser data";
  std::vector<std::string> notes;
  double max_time_difference_s = 0.001;
  double shift_margin_m = 0.5;
  mw::GridOptions g;
  mw::WorldOptions o;
  app.add_option("--log", log_path, "CARMEN log (FLASER / ROBOTLASER1 lines)")->required();
  app.add_option("--poses", poses_path, "sensor pose per scan: `t x y theta` per line")->required();
  app.add_option("--out", out_path, "world file to write (WKT)")->required();
  app.add_option("--svg", svg_path, "also draw the walls to this SVG");
  app.add_option("--png", png_path, "also draw the grid, the free region and the walls to this PNG");
  app.add_option("--title", title, "the header's first line");
  app.add_option("--note", notes, "a header line (repeatable)");
  app.add_option("--max-time-difference-s", max_time_difference_s, "a scan is used when a pose is this close in time")
      ->capture_default_str();
  app.add_option("--shift-margin-m", shift_margin_m, "shift so the walls' min corner is at (margin, margin)")
      ->capture_default_str();
  app.add_option("--cell-m", g.cell_m, "grid cell size")->capture_default_str();
  app.add_option("--max-range-m", g.max_range_m, "beams are used up to this range")->capture_default_str();
  app.add_option("--hit-log-odds", g.hit_log_odds)->capture_default_str();
  app.add_option("--miss-log-odds", g.miss_log_odds)->capture_default_str();
  app.add_option("--free-on-no-return", g.free_on_no_return, "trace no-return beams as free up to max range")
      ->capture_default_str();
  app.add_option("--occupied-log-odds", o.occupied_log_odds, "cells above are occupied")->capture_default_str();
  app.add_option("--free-log-odds", o.free_log_odds, "cells below are free")->capture_default_str();
  app.add_option("--min-obstacle-cells", o.min_obstacle_cells, "smaller occupied components are specks")
      ->capture_default_str();
  app.add_option("--max-unseen-pocket-m2", o.max_unseen_pocket_m2, "pockets without hits up to this become free")
      ->capture_default_str();
  app.add_option("--min-clutter-m2", o.min_clutter_m2, "smaller clutter is dropped")->capture_default_str();
  app.add_option("--spike-width-cells", o.spike_width_cells, "free spikes into unknown space this thin are cut")
      ->capture_default_str();
  app.add_option("--simplify-m", o.simplify_m, "Ramer-Douglas-Peucker tolerance")->capture_default_str();
  app.add_option("--robot-radius-m", o.robot_radius_m, "for the reachable area")->capture_default_str();
  app.add_option("--start-clearance-m", o.start_clearance_m, "START's distance to every wall")->capture_default_str();
  if (const auto code = pex::cli::parse_command_line(app, "pex-make-world", argc, argv)) return *code;
  if (const auto bad = g.validate(); !bad.empty()) {
    std::fprintf(stderr, "pex-make-world: %s\n", bad.c_str());
    return 64;
  }

  std::ifstream log_in(log_path);
  if (!log_in) {
    std::fprintf(stderr, "pex-make-world: cannot open %s\n", log_path.c_str());
    return EX_NOINPUT;
  }
  std::ifstream poses_in(poses_path);
  if (!poses_in) {
    std::fprintf(stderr, "pex-make-world: cannot open %s\n", poses_path.c_str());
    return EX_NOINPUT;
  }
  const ev::CarmenLog log = ev::parse_carmen_log(log_in);
  const ev::PoseFile poses = ev::read_poses(poses_in);
  if (log.malformed_lines > 0)
    std::fprintf(stderr, "pex-make-world: %zu malformed log lines (first: %s)\n", log.malformed_lines,
                 log.first_error.c_str());
  if (poses.malformed_lines > 0)
    std::fprintf(stderr, "pex-make-world: %zu malformed pose lines\n", poses.malformed_lines);

  // Each scan at the pose with the nearest time stamp. The poses are the
  // robot's; the scan's own laser pose relative to its odometry gives the mount.
  std::vector<mw::PosedScan> scans;
  std::vector<mw::Pose2> trajectory;
  for (const auto& laser : log.lasers) {
    const auto it = std::lower_bound(poses.poses.begin(), poses.poses.end(), laser.timestamp_s,
                                     [](const ev::StampedPose& p, double t) { return p.timestamp_s < t; });
    const ev::StampedPose* best = nullptr;
    if (it != poses.poses.end()) best = &*it;
    if (it != poses.poses.begin() &&
        (best == nullptr || std::abs(std::prev(it)->timestamp_s - laser.timestamp_s) <
                                std::abs(best->timestamp_s - laser.timestamp_s)))
      best = &*std::prev(it);
    if (best == nullptr || std::abs(best->timestamp_s - laser.timestamp_s) > max_time_difference_s) continue;
    const auto mount = pex::geometry::relative(laser.odometry, laser.laser_pose);
    const auto sensor = pex::geometry::compose(best->pose, mount);
    scans.push_back({sensor,
                     laser.angle_min_rad,
                     laser.angle_increment_rad,
                     laser.max_range_m,
                     laser.ranges_m});
    trajectory.push_back(best->pose);
  }
  std::fprintf(stderr, "pex-make-world: %zu of %zu scans matched a pose (of %zu)\n", scans.size(),
               log.lasers.size(), poses.poses.size());
  if (scans.empty()) return 1;

  const mw::OccupancyGrid grid = mw::build_grid(scans, g);
  auto result = mw::extract_world(grid, trajectory, o);
  if (const auto* err = std::get_if<std::string>(&result)) {
    std::fprintf(stderr, "pex-make-world: %s\n", err->c_str());
    return 1;
  }
  mw::World world = std::get<mw::World>(std::move(result));
  const double dx = std::round((shift_margin_m - world.min_x) * 100.0) / 100.0;
  const double dy = std::round((shift_margin_m - world.min_y) * 100.0) / 100.0;
  mw::translate(world, dx, dy);

  std::vector<std::string> header{title};
  for (const auto& n : notes) header.push_back(n);
  header.push_back(fmt("Size: walls span %.1f x %.1f m; %.0f edges in 1 boundary + %.0f obstacle polygons.",
                       world.max_x - world.min_x, world.max_y - world.min_y, static_cast<double>(world.edges()),
                       static_cast<double>(world.obstacles.size())));
  header.push_back(fmt("Free region %.1f m^2; a %.2f m disk's centre reaches %.1f m^2 from START.",
                       world.free_area_m2, o.robot_radius_m, world.reachable_area_m2));
  header.push_back(fmt("Frame: pex-slam's map frame shifted by (%.2f, %.2f) m; START is trajectory pose %.0f.", dx, dy,
                       static_cast<double>(world.start_index)));
  header.push_back(fmt("Scans: %.0f of %.0f; grid %.0f x %.0f cells.", static_cast<double>(scans.size()),
                       static_cast<double>(log.lasers.size()), grid.width(), grid.height()));
  header.push_back(fmt("Grid: cell_m %.3f, max_range_m %.1f, hit_log_odds %.2f, miss_log_odds %.2f,", g.cell_m,
                       g.max_range_m, g.hit_log_odds, g.miss_log_odds) +
                   fmt(" free_on_no_return %.0f.", g.free_on_no_return ? 1 : 0));
  header.push_back(fmt("Cells: occupied_log_odds %.2f, free_log_odds %.2f, min_obstacle_cells %.0f,",
                       o.occupied_log_odds, o.free_log_odds, o.min_obstacle_cells) +
                   fmt(" max_unseen_pocket_m2 %.3f, min_clutter_m2 %.4f, spike_width_cells %.0f.",
                       o.max_unseen_pocket_m2, o.min_clutter_m2, o.spike_width_cells));
  header.push_back(fmt("Walls: simplify_m %.3f; start_clearance_m %.2f; robot_radius_m %.2f.", o.simplify_m,
                       o.start_clearance_m, o.robot_radius_m));
  header.push_back(fmt("Cells: %.0f occupied, %.0f free, %.0f unknown; %.0f specks dropped,",
                       static_cast<double>(world.occupied_cells), static_cast<double>(world.free_cells),
                       static_cast<double>(world.unknown_cells), static_cast<double>(world.specks_dropped)) +
                   fmt(" %.0f spike cells cut, %.0f unseen pockets filled, %.0f tiny clutter dropped.",
                       static_cast<double>(world.spike_cells_cut), static_cast<double>(world.pockets_filled),
                       static_cast<double>(world.clutter_dropped)));
  header.push_back("Format: see worlds/README.md. Every edge is a wall: the LINESTRING closes the free space,");
  header.push_back("each POLYGON is clutter inside it.");

  // An output that cannot be written (no such folder, full disk): exit 73.
  const auto cannot_write = [](const std::string& path) {
    std::fprintf(stderr, "pex-make-world: cannot write %s\n", path.c_str());
    return EX_CANTCREAT;
  };
  std::ofstream out(out_path);
  out << mw::to_wkt(world, header);
  out.close();
  if (!out) return cannot_write(out_path);
  if (!svg_path.empty()) {
    std::ofstream svg(svg_path);
    svg << mw::to_svg(world);
    svg.close();
    if (!svg) return cannot_write(svg_path);
  }
  if (!png_path.empty()) {
    const auto pic = mw::render(world, grid, dx, dy, trajectory);
    pex::render_map::Image image{pic.width, pic.height, pic.rgb};
    const auto png = pex::render_map::encode_png(image);
    std::ofstream png_out(png_path, std::ios::binary);
    png_out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
    png_out.close();
    if (!png_out) return cannot_write(png_path);
  }
  std::printf(
      "{\"size_m\": [%.2f, %.2f], \"edges\": %zu, \"obstacles\": %zu, \"free_area_m2\": %.1f, "
      "\"reachable_area_m2\": %.1f, \"start\": [%.3f, %.3f, %.4f], \"trajectory_in_region\": %zu, \"trajectory_reachable\": %zu, \"scans\": %zu}\n",
      world.max_x - world.min_x, world.max_y - world.min_y, world.edges(), world.obstacles.size(), world.free_area_m2,
      world.reachable_area_m2, world.start.x_m, world.start.y_m, world.start.theta_rad, world.trajectory_in_region,
      world.trajectory_reachable, scans.size());
  return 0;
}
