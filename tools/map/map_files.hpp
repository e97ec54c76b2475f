#pragma once
// Map files: a MAP message (pex::polygon_map_t) as GeoJSON, and as a ROS
// map_server occupancy grid (PGM + YAML). The format is docs/map_files.md.
// Pure: text and bytes in and out, no files, no LCM calls, no clock.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <pex/polygon_map_t.hpp>

namespace pex::map_files {

// A map file that cannot be read: says where and why.
class MapFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Checks a MAP message: counts agree with arrays, at least 3 vertices a ring,
// finite coordinates, edge types obstacle or frontier, each polygon one outer
// ring followed by its holes. "" when good, else why not.
std::string check_map(const pex::polygon_map_t& map);

// Checks the map's geometry as a whole, as the mapper promises it: each
// polygon's outer ring counter-clockwise and its holes clockwise, no ring
// crossing or touching itself or another along an edge, holes inside their
// polygon, polygons apart but at points (OGC's rules, bg::is_valid). Rings
// are taken as they are, not mended as the explorer mends them. "" when
// valid, else why not (check_map's reason first).
std::string geometry_problem(const pex::polygon_map_t& map);

// GeoJSON (RFC 7946): a FeatureCollection with one Polygon Feature a polygon
// of the map, rings closed, coordinates in metres in the map frame. Each
// feature's properties give the type of every edge ("obstacle" | "frontier",
// edge i from vertex i to i + 1, ring by ring), the frame and the time; the
// collection carries the message's other fields. Doubles are written so that
// they read back bit for bit. Throws MapFileError for a map check_map() refuses.
std::string to_geojson(const pex::polygon_map_t& map);
// The inverse: to_geojson's output reads back into the identical message.
// Throws MapFileError (naming the feature and ring) for anything else.
pex::polygon_map_t from_geojson(std::string_view text);

// An occupancy grid as ROS map_server reads it: cells row by row, the top row
// (largest y) first, 0 = occupied, 254 = free, 205 = unknown.
struct OccupancyGrid {
  static constexpr std::uint8_t kOccupied = 0;
  static constexpr std::uint8_t kFree = 254;
  static constexpr std::uint8_t kUnknown = 205;
  int width = 0;
  int height = 0;
  double resolution_m = 0.05;  // cell side
  double origin_x_m = 0.0;     // the bottom-left corner of the bottom-left cell, map frame
  double origin_y_m = 0.0;
  std::vector<std::uint8_t> cells;  // width * height
  std::uint8_t at(int col, int row) const { return cells[static_cast<std::size_t>(row) * width + col]; }
  // The centre of a cell, in the map frame.
  double x_of(int col) const { return origin_x_m + (col + 0.5) * resolution_m; }
  double y_of(int row) const { return origin_y_m + (height - row - 0.5) * resolution_m; }
};

// Free space is every cell whose centre lies inside the map (even-odd over
// every ring, so holes are not free); every cell an obstacle edge passes
// through is occupied; the rest (outside, beyond frontiers) unknown. The grid
// spans the map plus `margin_m`. Throws MapFileError for a bad map, a
// resolution not above 0, or a grid over `max_cells` cells.
OccupancyGrid rasterise(const pex::polygon_map_t& map, double resolution_m, double margin_m = 0.5,
                        std::int64_t max_cells = 400'000'000);

// Binary PGM (P5, maxval 255), and map_server's YAML naming `image_file`.
std::string to_pgm(const OccupancyGrid& grid);
std::string to_yaml(const OccupancyGrid& grid, const std::string& image_file);
// Reads a P5 PGM (comments allowed) into width, height and cells; throws MapFileError.
OccupancyGrid from_pgm(std::string_view bytes);

}  // namespace pex::map_files
