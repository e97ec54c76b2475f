// One laser scan -> the free-space polygon the mapper inserts
// (mapping::scan_to_polygon), on scans of any shape: NaN, inf, negative and
// huge ranges, zero, negative or absurd angle steps, sweeps beyond a turn,
// sensor poses of any value, and the options a config may set.
//
// Input: a flags byte (bit 0: angle_min, 1: angle_increment, 2: the sensor
// pose as any doubles, else small; 3: obstacle_range_m on; 4: return_margin_m
// on; 5: free_range_m from a byte; 6: no refit; 7: a small max_beams), the
// beam count (2 bytes, up to 4095), then a byte per beam: range = byte x 0.1 m,
// 255 = the next 4 bytes as any float.
// Invariants: nothing throws; a refusal says why; a polygon is valid to
// bg::is_valid, counter-clockwise, without holes, typed on every edge, finite,
// and within the farthest range it may reach of the sensor.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <boost/geometry.hpp>

#include "fuzz_check.hpp"
#include "fuzz_input.hpp"
#include "mapping/known_walls.hpp"
#include "mapping/scan_polygon.hpp"

namespace {

using namespace pex;
namespace bg = boost::geometry;

float any_float(fuzz::Input& in) {
  const std::uint32_t bits = in.u32();
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  const std::uint8_t flags = in.byte();
  mapping::ScanPolygonOptions options;
  if (flags & 8) options.obstacle_range_m = 1.0 + in.byte() * 0.1;
  if (flags & 16) options.return_margin_m = in.byte() * 0.001;
  if (flags & 32) options.free_range_m = in.byte() * 0.1;
  if (flags & 64) options.least_squares_refit = false;
  if (flags & 128) options.max_beams = 1 + in.byte();
  const double angle_min = (flags & 1) ? in.any_double() : -2.356 + in.byte() * 0.01;
  const double angle_increment = (flags & 2) ? in.any_double() : 0.001 + in.byte() * 0.0005;
  geometry::Pose2 sensor{0.0, 0.0, 0.0};
  if (flags & 4) {
    sensor = {in.any_double(), in.any_double(), in.any_double()};
  } else {
    sensor = {static_cast<std::int8_t>(in.byte()) * 0.5, static_cast<std::int8_t>(in.byte()) * 0.5,
              static_cast<std::int8_t>(in.byte()) * 0.05};
  }
  const int beams = in.u16() % 4096;
  std::vector<float> ranges;
  ranges.reserve(static_cast<std::size_t>(beams));
  for (int i = 0; i < beams && !in.empty(); ++i) {
    const std::uint8_t r = in.byte();
    ranges.push_back(r == 255 ? any_float(in) : static_cast<float>(r * 0.1));
  }
  // Walls the map holds, from what input is left: the beams without a
  // return stop at them (known_walls.hpp).
  std::vector<mapping::KnownWall> walls;
  for (int k = in.empty() ? 0 : in.byte() % 8; k > 0 && !in.empty(); --k) {
    auto near = [&] { return static_cast<std::int8_t>(in.byte()) * 0.05; };
    const double ax = sensor.x_m + near(), ay = sensor.y_m + near(), bx = sensor.x_m + near(), by = sensor.y_m + near();
    walls.push_back({mapping::Point(ax, ay), mapping::Point(bx, by)});
  }
  mapping::NoReturnExtents stopped;
  try {
    stopped = mapping::no_return_extents(ranges, angle_min, angle_increment, sensor, options, walls);
  } catch (...) {
    PEX_FUZZ_CHECK(false, "no_return_extents threw");
  }
  PEX_FUZZ_CHECK(stopped.extent_m.empty() || stopped.extent_m.size() == ranges.size(), "extents not one per beam");
  for (const float e : stopped.extent_m)
    PEX_FUZZ_CHECK(e <= options.free_range_m * (1.0 + 1e-6) && e >= 0.0f, "an extent beyond the free range");
  mapping::ScanPolygonResult result;
  try {
    result = mapping::scan_to_polygon(ranges, angle_min, angle_increment, sensor, options, stopped.extent_m);
  } catch (...) {
    PEX_FUZZ_CHECK(false, "scan_to_polygon threw (it must refuse with a reason instead)");
  }
  if (!result.ok) {
    PEX_FUZZ_CHECK(!result.error.empty(), "refused without a reason");
    return 0;
  }
  const mapping::TypedPolygon& p = result.polygon;
  PEX_FUZZ_CHECK(p.geometry.inners().empty(), "a scan polygon with holes");
  PEX_FUZZ_CHECK(p.edge_types.size() == 1 && p.edge_types[0].size() + 1 == p.geometry.outer().size(),
                 "edge types do not match the ring");
  PEX_FUZZ_CHECK(bg::area(p.geometry) > 0.0, "not counter-clockwise or empty");
  std::string why;
  PEX_FUZZ_CHECK(bg::is_valid(p.geometry, why), "an invalid polygon taken as ok: " + why);
  // The farthest a vertex may lie from the sensor: a return, a free arc, or
  // where two fitted lines meet (refit_max_shift_m beyond an RDP point).
  const double reach = std::max({options.range_max_m, options.free_range_m}) + options.refit_max_shift_m + 1e-6;
  for (const auto& v : p.geometry.outer()) {
    PEX_FUZZ_CHECK(std::isfinite(v.x()) && std::isfinite(v.y()), "a vertex is not finite");
    PEX_FUZZ_CHECK(std::hypot(v.x() - sensor.x_m, v.y() - sensor.y_m) <= reach * (1.0 + 1e-9),
                   "a vertex beyond the scan's reach");
  }
  return 0;
}
