#pragma once
// A simulator world from real laser data: scans at known poses are ray-traced
// into a log-odds occupancy grid; the cells observed free and connected to the
// start become the world's free space, and the boundary of that region (with
// its holes: clutter, pillars) becomes the walls, traced cell edge by cell edge,
// cut to the midpoints of the edges (marching squares) and simplified by
// Ramer–Douglas–Peucker. Pure algorithm: no I/O, no clock.
//
// Why the boundary of the *observed free* region and not of the occupied
// cells: it is closed by construction. Where the laser saw a wall the boundary
// runs along the wall's face; where the data ends (an opening towards space
// never observed: a door to nowhere, the view through a window) the boundary
// closes the opening at the last free cell, so a robot cannot leave through it.
// Openings between observed free cells (inner doors, gaps the laser saw
// through) stay open.
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "geometry/pose2.hpp"

namespace pex::make_world {

using geometry::Pose2;

// One laser scan at a known sensor pose (world frame). Beam i points at
// sensor.theta_rad + angle_min_rad + i * angle_increment_rad.
struct PosedScan {
  Pose2 sensor;
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  double no_return_m = 0.0;  // readings >= this mean "no return"
  std::vector<float> ranges_m;
};

struct GridOptions {
  double cell_m = 0.05;
  // Beams are used up to this distance: a longer reading marks the cells up to
  // it free and makes no hit (far hits smear walls by the heading error).
  double max_range_m = 12.0;
  double min_range_m = 0.05;  // shorter readings are dropped
  double hit_log_odds = 0.9;   // added to the cell of a beam's end point
  // Added to every cell a beam crosses before its end point. Small against
  // the hit: thin clutter (chair and table legs) is hit by only some of the
  // beams that cross its cell and would be erased by a larger one (-0.4 keeps
  // walls but loses the furniture of the Intel lab).
  double miss_log_odds = -0.15;
  // A no-return beam marks cells free up to max_range_m when true; when false
  // it is dropped (a no-return says little indoors: glass, black surfaces).
  bool free_on_no_return = false;
  double margin_m = 1.0;  // the grid reaches this far beyond every beam
  std::string validate() const;  // "" when usable
};

// Log-odds per cell; cell (ix, iy) covers [origin_x + ix*cell, +cell) × [origin_y + iy*cell, +cell).
class OccupancyGrid {
 public:
  OccupancyGrid(double origin_x_m, double origin_y_m, int width, int height, double cell_m);

  int width() const { return width_; }
  int height() const { return height_; }
  double cell_m() const { return cell_m_; }
  double origin_x_m() const { return origin_x_m_; }
  double origin_y_m() const { return origin_y_m_; }
  bool contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width_ && iy < height_; }
  float log_odds(int ix, int iy) const { return cells_[index(ix, iy)]; }
  void add(int ix, int iy, float value) { cells_[index(ix, iy)] += value; }
  // The cell holding (x, y); may be outside the grid.
  int cell_x(double x_m) const;
  int cell_y(double y_m) const;

  // Ray-traces one scan (Amanatides–Woo cell walk): misses along each beam,
  // a hit at its end point. Beams leaving the grid are cut at its edge.
  void integrate(const PosedScan& scan, const GridOptions& options);

 private:
  std::size_t index(int ix, int iy) const { return static_cast<std::size_t>(iy) * width_ + ix; }
  double origin_x_m_, origin_y_m_;
  int width_, height_;
  double cell_m_;
  std::vector<float> cells_;
};

// A grid covering every beam (up to max_range_m) of every scan, plus the
// margin, with all scans integrated.
OccupancyGrid build_grid(const std::vector<PosedScan>& scans, const GridOptions& options);

struct WorldOptions {
  double occupied_log_odds = 0.5;  // a cell above is occupied
  double free_log_odds = -0.5;     // a cell below is free; in between unknown
  // Occupied 8-connected components with fewer cells than this are specks
  // (noise, a person's legs seen once): they become unknown.
  int min_obstacle_cells = 3;
  // Pockets inside the free region (not free, 8-connected, not touching the
  // outside) with no occupied cell and at most this area are gaps between
  // rays: they become free. Pockets holding occupied cells are clutter.
  double max_unseen_pocket_m2 = 0.5;
  // Clutter (a pocket holding occupied cells) smaller than this is dropped.
  double min_clutter_m2 = 0.0075;
  // Free cells that are a free spike: a run of free space at most this many
  // cells wide poking into unknown space (a fan of rays through a doorway,
  // seen once) is cut off by a morphological opening of the free cells that
  // touch unknown space; 0 turns it off.
  int spike_width_cells = 1;
  double simplify_m = 0.03;        // Ramer–Douglas–Peucker tolerance
  double robot_radius_m = 0.25;    // for the reachable area
  double start_clearance_m = 0.6;  // START is the first trajectory pose this far from every wall
};

struct Point {
  double x = 0.0;
  double y = 0.0;
};
using Ring = std::vector<Point>;  // closed implicitly: the last point joins the first

enum class CellClass : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct World {
  Ring boundary;                // the free region's outer boundary, counter-clockwise
  std::vector<Ring> obstacles;  // its holes (clutter, pillars, wall blocks inside), counter-clockwise
  Pose2 start;
  std::size_t start_index = 0;  // which trajectory pose is START
  double free_area_m2 = 0.0;    // area of the free region (cells)
  double reachable_area_m2 = 0.0;  // area of the cells a robot_radius disk's centre reaches from START
  double min_x = 0.0, min_y = 0.0, max_x = 0.0, max_y = 0.0;  // bounds of the walls
  // Bookkeeping for the header and the report.
  std::size_t occupied_cells = 0, free_cells = 0, unknown_cells = 0;
  std::size_t specks_dropped = 0, pockets_filled = 0, clutter_dropped = 0, spike_cells_cut = 0;
  std::size_t trajectory_in_region = 0;     // trajectory poses whose cell is in the free region
  std::size_t trajectory_reachable = 0;     // ... and is reached by the disk's centre from START
  std::size_t edges() const;             // wall segments in all rings
  // Per cell (row-major, grid order): in the free region; reachable by the disk's centre.
  std::vector<std::uint8_t> region, reachable;
  std::vector<CellClass> classes;  // after specks were dropped
};

// The world from a grid and the trajectory the scans were taken along (the
// seed of the free region is the first trajectory pose in a free cell). An
// error when no trajectory pose is in a free cell or none is clear enough.
std::variant<World, std::string> extract_world(const OccupancyGrid& grid, const std::vector<Pose2>& trajectory,
                                               const WorldOptions& options);

// Translates every ring, the start and the bounds by (dx, dy).
void translate(World& world, double dx_m, double dy_m);

// Shoelace area (positive counter-clockwise).
double signed_area(const Ring& ring);

// Ramer–Douglas–Peucker on a closed ring: no dropped point is farther than
// tolerance_m from the simplified ring. Rings of fewer than 4 points are kept.
Ring simplify_ring(const Ring& ring, double tolerance_m);

// WKT lines: `START x y theta`, the boundary as a closed LINESTRING, each
// obstacle as a POLYGON; `header` lines are written first as '#' comments.
std::string to_wkt(const World& world, const std::vector<std::string>& header);

// An SVG picture of the walls (black) and START (red), in world coordinates.
std::string to_svg(const World& world);

// A picture of the grid, one pixel per cell, top row = largest y: unknown
// grey, occupied black, free white, free region pale blue, cells the disk's
// centre reaches pale green, walls red, START a red cross, the trajectory
// (grid frame) dark blue where the disk's centre reaches and magenta where it
// does not. `dx_m, dy_m` is the translation applied to `world` after
// extraction (to place its walls back on the grid).
struct Picture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // 3 bytes a pixel, top row first
};
Picture render(const World& world, const OccupancyGrid& grid, double dx_m, double dy_m,
               const std::vector<Pose2>& trajectory = {});

}  // namespace pex::make_world
