// An operator's keep-out file (the explorer's `keep_out_file`):
// planning::parse_keep_out, then what every plan does with it — take it out
// of a map (planning::without_keep_out).
//
// Input: the file's text; the robot starts at (1.5, -2, 0.3 rad) in the
// file's frame, lines are 0.05 m wide.
// Invariants: nothing crashes; the result is an error naming the file (and,
// for a line's own fault, the line), or keep-out polygons that are valid,
// every edge an obstacle, every coordinate within the map overlay's extent,
// none when nothing was read; and taking them out of a 40 x 40 m map around
// the start succeeds, leaving no more area than the map had: a file the
// explorer takes never fails a plan.
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

#include "fuzz_check.hpp"
#include "mapping/edge_overlay.hpp"
#include "planning/keep_out.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pex;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::string origin = "fuzz.wkt";
  const auto parsed = planning::parse_keep_out(text, origin, geometry::Pose2{1.5, -2.0, 0.3}, 0.05);
  if (const auto* e = std::get_if<planning::KeepOutError>(&parsed)) {
    PEX_FUZZ_CHECK(e->message.rfind(origin + ":", 0) == 0, "error without the file: " + e->message);
    return 0;
  }
  const auto& k = std::get<planning::KeepOut>(parsed);
  PEX_FUZZ_CHECK(k.lines >= 0 && k.areas >= 0, "negative counts");
  if (k.lines == 0 && k.areas == 0) PEX_FUZZ_CHECK(k.obstacles.empty(), "polygons from nothing read");
  std::string why;
  PEX_FUZZ_CHECK(mapping::is_valid(k.obstacles, &why), "invalid keep-out: " + why);
  for (const auto& polygon : k.obstacles) {
    for (const auto& ring : polygon.edge_types)
      for (const auto t : ring) PEX_FUZZ_CHECK(t == mapping::EdgeType::kObstacle, "an edge not typed obstacle");
    boost::geometry::for_each_point(polygon.geometry, [](const mapping::Point& p) {
      PEX_FUZZ_CHECK(std::abs(p.x()) < mapping::kOverlayMaxCoordinateM &&
                         std::abs(p.y()) < mapping::kOverlayMaxCoordinateM,
                     "a point beyond the overlay's extent");
    });
  }

  mapping::TypedPolygon room;
  room.geometry.outer() = {mapping::Point(-20, -20), mapping::Point(20, -20), mapping::Point(20, 20),
                           mapping::Point(-20, 20), mapping::Point(-20, -20)};
  room.edge_types = {std::vector<mapping::EdgeType>(4, mapping::EdgeType::kFrontier)};
  const mapping::TypedMultiPolygon map{room};
  const auto cut = planning::without_keep_out(map, k.obstacles);
  PEX_FUZZ_CHECK(cut.ok, "the keep-out could not be taken out of a map: " + cut.error);
  PEX_FUZZ_CHECK(mapping::area(cut.polygons) <= mapping::area(map) + 1e-6, "the map grew");
  return 0;
}
