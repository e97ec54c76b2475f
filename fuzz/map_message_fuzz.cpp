// A MAP message (pex.polygon_map_t) as the explorer takes it: bytes through the
// bounded decoder, then explorer::decode_map into the checked typed polygons
// the planner works on.
//
// Input: byte 0 says how the rest is read. With bit 7 set, it is the LCM
// payload of a polygon_map_t. Otherwise it describes the message: a ring
// count, then per ring its polygon index, hole flag, vertex count and
// vertices (a byte of grid coordinates, or two doubles of any value) with
// edge types, so the fuzzer reaches geometry without building the encoding.
// Invariants: nothing crashes; the result is an error with a reason, or
// polygons that are valid (Boost.Geometry), typed on every edge, outer rings
// counter-clockwise and holes clockwise, all coordinates finite and within
// the map's extent, no more vertices than the limit.
#include <cmath>
#include <cstdint>
#include <string>

#include <boost/geometry.hpp>
#include <pex/polygon_ring_t.hpp>

#include "fuzz_check.hpp"
#include "fuzz_input.hpp"
#include "map_message.hpp"

namespace {

using namespace pex;

pex::polygon_map_t describe(fuzz::Input& in, std::uint8_t head) {
  pex::polygon_map_t msg{};
  msg.utime = 1;
  msg.nrings = head % 8;
  for (int r = 0; r < msg.nrings; ++r) {
    pex::polygon_ring_t ring{};
    const std::uint8_t b = in.byte();
    ring.polygon = b % 4;
    ring.hole = (b >> 2) & 1;
    const bool any_values = (b >> 3) & 1;
    ring.nvertices = in.byte() % 16;
    for (int i = 0; i < ring.nvertices; ++i) {
      if (any_values) {
        ring.x.push_back(in.any_double());
        ring.y.push_back(in.any_double());
      } else {
        const std::uint8_t g = in.byte();
        ring.x.push_back((g & 0xF) * 0.5);
        ring.y.push_back((g >> 4) * 0.5);
      }
      const std::uint8_t t = in.byte();
      ring.edge_type.push_back(static_cast<std::int8_t>(t < 250 ? t % 2 : t));
    }
    if ((b >> 4) == 15) ring.nvertices += 1;  // a count that disagrees with the arrays
    msg.rings.push_back(std::move(ring));
  }
  return msg;
}

void check(const explorer::DecodedMap& d, const explorer::MapDecodeOptions& options) {
  if (!d.ok) {
    PEX_FUZZ_CHECK(!d.error.empty(), "refused without a reason");
    return;
  }
  std::size_t vertices = 0;
  for (const auto& p : d.polygons) {
    std::string why;
    PEX_FUZZ_CHECK(mapping::is_valid(p, &why), "an invalid polygon taken: " + why);
    PEX_FUZZ_CHECK(mapping::types_match_rings(p), "types");
    PEX_FUZZ_CHECK(boost::geometry::area(p.geometry.outer()) > 0, "outer ring not counter-clockwise");
    for (const auto& h : p.geometry.inners()) PEX_FUZZ_CHECK(boost::geometry::area(h) < 0, "hole not clockwise");
    auto check_ring = [&](const mapping::Ring& ring) {
      vertices += ring.size() - 1;
      for (const auto& pt : ring)
        PEX_FUZZ_CHECK(std::abs(pt.x()) <= options.max_abs_coordinate_m && std::abs(pt.y()) <= options.max_abs_coordinate_m,
                       "vertex (" + std::to_string(pt.x()) + ", " + std::to_string(pt.y()) + ")");
    };
    check_ring(p.geometry.outer());
    for (const auto& h : p.geometry.inners()) check_ring(h);
  }
  PEX_FUZZ_CHECK(static_cast<std::int64_t>(vertices) <= options.max_vertices, "vertices");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input in(data, size);
  const std::uint8_t head = in.byte();
  pex::polygon_map_t msg{};
  if (head & 0x80) {
    const std::string_view payload = in.rest();
    if (msg.decode(payload.data(), 0, static_cast<int>(payload.size())) != static_cast<int>(payload.size()))
      return 0;  // refused by the decoder: lcm_message covers that path
  } else {
    msg = describe(in, head);
  }
  explorer::MapDecodeOptions options;
  options.max_vertices = 64;  // small, so the fuzzer meets the limit
  check(explorer::decode_map(msg, options), options);
  return 0;
}
