#pragma once
// Keep-out lines and areas: what an operator knows and the laser cannot see.
// Clean glass at a slant returns no beam (docs/exploration.md, "Session 48:
// glass"), a stairwell's drop and a low table's top are below the scan plane,
// and some rooms are not to be entered. The operator draws them (WKT, as a
// world file's walls) in a frame of their choice and says where the robot
// starts in it; every plan then treats them as walls: the C-space keeps the
// robot's radius and margin from them, no path crosses them and no frontier
// behind them is a goal unless another way leads there. Pure: text in,
// polygons out; the daemon reads the file.
#include <memory>
#include <string>
#include <string_view>
#include <variant>

#include "geometry/pose2.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::planning {

struct KeepOut {
  // In the map frame (origin at the robot's start pose), every edge an
  // obstacle; lines as strips line_width_m wide.
  mapping::TypedMultiPolygon obstacles;
  int lines = 0;  // segments read
  int areas = 0;  // polygons read
};

struct KeepOutError {
  std::string message;  // "<origin>:<line>: what is wrong"
};

// Parses a keep-out file's text: '#' comment lines, blank lines, and one WKT
// geometry per line — LINESTRING or MULTILINESTRING (lines the robot must not
// cross, each segment a strip line_width_m wide) and POLYGON or MULTIPOLYGON
// (areas it must not enter; rings closed). Coordinates are metres in the
// file's frame, in which the robot starts at `start_in_file` (the map frame is
// the robot's start pose). Non-finite or absurd (> 1e5 m) coordinates, an
// unclosed ring, another geometry or bad WKT are errors naming the line.
std::variant<KeepOut, KeepOutError> parse_keep_out(std::string_view text, const std::string& origin,
                                                   const geometry::Pose2& start_in_file, double line_width_m);

// `map` minus the keep-out obstacles (their edges typed obstacle); `map`
// itself when there are none or the difference fails (`failed` then set).
mapping::TypedMultiPolygon without_keep_out(const mapping::TypedMultiPolygon& map,
                                            const mapping::TypedMultiPolygon& keep_out, bool* failed = nullptr);

}  // namespace pex::planning
