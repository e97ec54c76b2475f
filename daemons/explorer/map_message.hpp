#pragma once
// MAP message (pex::polygon_map_t) -> typed polygons for planning, checked:
// the explorer plans only on geometry it has validated.
#include <cstdint>
#include <string>

#include <pex/polygon_map_t.hpp>

#include "mapping/typed_polygon.hpp"

namespace pex::explorer {

struct MapDecodeOptions {
  std::int64_t max_vertices = 200'000;  // a larger map is refused (oversize message)
  // A vertex farther from the origin than this makes the message bad: the
  // mapper's tiles start within 1e5 m of it (tile_origin_m) and no building
  // spans 1e6 m, while the planner's integer offset (Clipper) and areas
  // overflow on coordinates such as 1e300 (issue 12, fuzz target map_message).
  double max_abs_coordinate_m = 1e6;
};

struct DecodedMap {
  bool ok = false;
  std::string error;                   // why not ok: nothing usable in the message
  mapping::TypedMultiPolygon polygons;
  int rings_reoriented = 0;            // rings given in the wrong direction, reversed
  int rings_dropped = 0;               // fewer than 3 distinct vertices
  int polygons_dropped = 0;            // invalid geometry (self-intersection, no outer ring, ...)
};

// Rings are grouped by their `polygon` index (in order of first appearance);
// each polygon needs exactly one outer ring. Non-finite coordinates or ones
// beyond max_abs_coordinate_m, unknown
// edge types, array sizes that disagree with the counts, or more than
// max_vertices vertices make the whole message bad (ok = false). Single
// broken polygons are dropped and counted, the rest is kept. A ring in the
// wrong direction is reversed with its edge types.
DecodedMap decode_map(const pex::polygon_map_t& msg, const MapDecodeOptions& options = {});

// The inverse, for tests and tools: rings open (no repeated first vertex).
pex::polygon_map_t encode_map(const mapping::TypedMultiPolygon& polygons, std::int64_t utime);

}  // namespace pex::explorer
