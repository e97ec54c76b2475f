#include "initial_map.hpp"

#include <stdexcept>

#include <spdlog/spdlog.h>

#include "map_files.hpp"
#include "map_source.hpp"
#include "runtime/config.hpp"

namespace pex::polygon_mapper {

mapping::TypedMultiPolygon polygons_of(const pex::polygon_map_t& map) {
  if (auto why = map_files::check_map(map); !why.empty()) throw std::invalid_argument(why);
  mapping::TypedMultiPolygon out;
  for (const auto& r : map.rings) {
    if (!r.hole) out.emplace_back();  // check_map: an outer ring, then its holes
    auto& polygon = out.back();
    auto& ring = r.hole ? polygon.geometry.inners().emplace_back() : polygon.geometry.outer();
    std::vector<mapping::EdgeType> types;
    for (std::size_t i = 0; i < r.x.size(); ++i) {
      ring.push_back({r.x[i], r.y[i]});
      types.push_back(r.edge_type[i] == pex::polygon_ring_t::EDGE_FRONTIER ? mapping::EdgeType::kFrontier
                                                                           : mapping::EdgeType::kObstacle);
    }
    ring.push_back(ring.front());  // closed, as the polygon type is
    polygon.edge_types.push_back(std::move(types));
  }
  return out;
}

void start_from_initial_map(Mapper& mapper) {
  const std::string& path = mapper.options().initial_map_file;
  if (path.empty()) return;
  mapping::TypedMultiPolygon polygons;
  try {
    polygons = polygons_of(map_files::read_map_file(path));
  } catch (const std::exception& e) {
    throw runtime::ConfigError("initial_map_file: " + std::string(e.what()));
  }
  if (auto why = mapper.start_from(polygons); !why.empty()) {
    spdlog::warn("initial_map_file {} not taken up: {}", path, why);
    return;
  }
  spdlog::info("started from the saved map {}: {} polygons, {:.1f} m2 free", path, polygons.size(),
               mapper.map().free_area_m2());
}

}  // namespace pex::polygon_mapper
