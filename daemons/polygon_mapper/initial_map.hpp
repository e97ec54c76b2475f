#pragma once
// The mapper's start from a saved map (initial_map_file): a MAP saved by
// `pex-map save` (GeoJSON, docs/map_files.md), taken up when no checkpoint was.
#include <pex/polygon_map_t.hpp>

#include "mapper.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::polygon_mapper {

// The polygons of a MAP message, each outer ring with its holes and edge
// types, as PolygonMap::insert takes them. Throws std::invalid_argument for a
// message map_files::check_map refuses.
mapping::TypedMultiPolygon polygons_of(const pex::polygon_map_t& map);

// Reads mapper.options().initial_map_file (nothing if "") and starts the map
// from it (Mapper::start_from). Throws runtime::ConfigError naming the file
// and why if it cannot be read or is no map file (exit 78); logs and goes on
// if the mapper refuses it (a map is already held).
void start_from_initial_map(Mapper& mapper);

}  // namespace pex::polygon_mapper
