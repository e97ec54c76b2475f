// A simulator world file (worlds/*.wkt, pex-sim's `world` key): sim::parse_world,
// then what pex-sim does with a world it took (the R-tree of walls, the start
// clearance, a laser sweep from the start).
//
// Input: the file's text.
// Invariants: nothing crashes; the result is an error naming the file and a
// line, or a world whose walls are finite, within +-1e5 m, of non-zero
// length and inside its bounds, with a finite start within the bounds; every
// ray cast in it is a distance in [0, max range], and a laser beam, which
// passes glass at a slant, reaches at least as far as the body's ray.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>
#include <variant>

#include "fuzz_check.hpp"
#include "sim/sim.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pex;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::string origin = "fuzz.wkt";
  const auto parsed = sim::parse_world(text, origin);
  if (const auto* e = std::get_if<sim::WorldError>(&parsed)) {
    PEX_FUZZ_CHECK(e->message.rfind(origin + ":", 0) == 0, "error without the file: " + e->message);
    return 0;
  }
  const auto& w = std::get<sim::World>(parsed);
  PEX_FUZZ_CHECK(!w.walls.empty(), "a world without walls");
  auto in_bounds = [&](double x, double y) {
    return std::isfinite(x) && std::isfinite(y) && x >= w.min_x && x <= w.max_x && y >= w.min_y && y <= w.max_y;
  };
  for (const auto& wall : w.walls) {
    for (double c : {wall.x0, wall.y0, wall.x1, wall.y1})
      PEX_FUZZ_CHECK(std::isfinite(c) && std::abs(c) <= 1e5, "coordinate " + std::to_string(c));
    PEX_FUZZ_CHECK(wall.x0 != wall.x1 || wall.y0 != wall.y1, "a zero-length wall");
    PEX_FUZZ_CHECK(in_bounds(wall.x0, wall.y0) && in_bounds(wall.x1, wall.y1), "a wall outside the bounds");
  }
  PEX_FUZZ_CHECK(in_bounds(w.start.x_m, w.start.y_m) && std::isfinite(w.start.theta_rad), "start outside the bounds");

  const sim::RayCaster walls(w);
  PEX_FUZZ_CHECK(walls.wall_count() == w.walls.size(), "walls lost in the index");
  (void)sim::check_start_clearance(w, walls, 0.2);
  constexpr double kMaxRange = 20.0;
  for (int i = 0; i < 16; ++i) {
    const double r = walls.cast(w.start.x_m, w.start.y_m, w.start.theta_rad + i * std::numbers::pi / 8, kMaxRange);
    PEX_FUZZ_CHECK(r >= 0 && r <= kMaxRange, "ray " + std::to_string(r));
    const double beam = walls.cast_beam(w.start.x_m, w.start.y_m, w.start.theta_rad + i * std::numbers::pi / 8,
                                        kMaxRange, 10.0 * std::numbers::pi / 180.0);
    PEX_FUZZ_CHECK(beam >= r && beam <= kMaxRange, "beam " + std::to_string(beam) + " short of the ray " + std::to_string(r));
  }
  const double c = walls.clearance(w.start.x_m, w.start.y_m, kMaxRange);
  PEX_FUZZ_CHECK(c >= 0 && c <= kMaxRange, "clearance " + std::to_string(c));
  return 0;
}
