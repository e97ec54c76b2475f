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
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "geometry/pose2.hpp"
#include "mapping/typed_ops.hpp"
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

// `map` minus the keep-out obstacles, their edges typed obstacle. Not
// checked with bg::is_valid, as the live view's union is not (it only feeds
// the C-space's offset); not ok, with why, when the overlay fails: a plan
// must then not fall back to the map without them (a line drawn at a
// stairwell's edge).
mapping::TypedOpResult without_keep_out(const mapping::TypedMultiPolygon& map,
                                        const mapping::TypedMultiPolygon& keep_out);

// Every shape united, pairwise by the map's own overlay (typed_union,
// which checks its result): a keep-out file's strips and areas, the guard's
// marks. Not ok, with why, when an overlay fails.
mapping::TypedOpResult unite_all(std::vector<mapping::TypedMultiPolygon> shapes);

// without_keep_out() of the last map and keep-out it was asked for, kept:
// the difference runs over the whole map, and the explorer plans on each MAP
// (1 Hz) more than once (a goal selected, then followed; a tight plan). Not
// thread-safe: one per planning thread (PlanCache).
class KeepOutCache {
 public:
  const mapping::TypedOpResult& without_keep_out(const std::shared_ptr<const mapping::TypedMultiPolygon>& map,
                                                 const std::shared_ptr<const mapping::TypedMultiPolygon>& keep_out);
  std::int64_t hits() const { return hits_; }
  std::int64_t misses() const { return misses_; }

 private:
  // Held, so that no other map can come to have their addresses.
  std::shared_ptr<const mapping::TypedMultiPolygon> map_, keep_out_;
  mapping::TypedOpResult result_;
  std::int64_t hits_ = 0, misses_ = 0;
};

}  // namespace pex::planning
