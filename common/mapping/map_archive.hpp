#pragma once
// Polygon maps in checkpoints (archive/byte_archive.hpp): the tiles' free and
// obstacle layers as they are, point for point, so a restored map is the map
// that was saved (its planning layer is derived again, from the same layers,
// by the same code: the same polygons). Reading checks what it reads: finite
// coordinates, known edge types, valid polygons, the same tile grid; anything
// else is an archive::ArchiveError, never a half-read map.
#include "archive/byte_archive.hpp"
#include "mapping/polygon_map.hpp"
#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

void write_typed_multipolygon(archive::ByteWriter& out, const TypedMultiPolygon& polygons);
// `what` names the layer in error messages.
TypedMultiPolygon read_typed_multipolygon(archive::ByteReader& in, const std::string& what);

void write_polygon_map(archive::ByteWriter& out, const PolygonMap& map);
// The map's options come from the caller (the configuration in force); the
// archive's tile grid (size, origin) must be theirs, or the tiles would be cut
// on other lines.
PolygonMap read_polygon_map(archive::ByteReader& in, const PolygonMapOptions& options);

}  // namespace pex::mapping
