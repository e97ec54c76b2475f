#include "mapping/map_archive.hpp"

#include <cmath>

namespace pex::mapping {

using archive::ArchiveError;

namespace {

void write_ring(archive::ByteWriter& out, const Ring& ring, const std::vector<EdgeType>& types) {
  out.put<std::uint64_t>(ring.size());
  for (const Point& p : ring) {
    out.put<double>(p.x());
    out.put<double>(p.y());
  }
  out.put<std::uint64_t>(types.size());
  for (const EdgeType t : types) out.put<std::uint8_t>(static_cast<std::uint8_t>(t));
}

void read_ring(archive::ByteReader& in, const std::string& what, Ring& ring, std::vector<EdgeType>& types) {
  const auto points = in.get_count(2 * sizeof(double));
  ring.reserve(points);
  for (std::uint64_t i = 0; i < points; ++i) {
    const double x = in.get<double>(), y = in.get<double>();
    if (!std::isfinite(x) || !std::isfinite(y)) throw ArchiveError(what + ": a vertex is not finite");
    ring.emplace_back(x, y);
  }
  const auto n = in.get_count(1);
  types.reserve(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    const auto t = in.get<std::uint8_t>();
    if (t > static_cast<std::uint8_t>(EdgeType::kBorder))
      throw ArchiveError(what + ": edge type " + std::to_string(t) + " is unknown");
    types.push_back(static_cast<EdgeType>(t));
  }
}

}  // namespace

void write_typed_multipolygon(archive::ByteWriter& out, const TypedMultiPolygon& polygons) {
  out.put<std::uint64_t>(polygons.size());
  for (const TypedPolygon& p : polygons) {
    out.put<std::uint64_t>(p.geometry.inners().size());
    write_ring(out, p.geometry.outer(), p.edge_types.at(0));
    for (std::size_t h = 0; h < p.geometry.inners().size(); ++h)
      write_ring(out, p.geometry.inners()[h], p.edge_types.at(1 + h));
  }
}

TypedMultiPolygon read_typed_multipolygon(archive::ByteReader& in, const std::string& what) {
  // Smallest polygon on the wire: the hole count and two empty rings' counts.
  const auto count = in.get_count(3 * sizeof(std::uint64_t));
  TypedMultiPolygon polygons(count);
  for (TypedPolygon& p : polygons) {
    const auto holes = in.get_count(2 * sizeof(std::uint64_t));
    p.edge_types.resize(1 + holes);
    p.geometry.inners().resize(holes);
    read_ring(in, what, p.geometry.outer(), p.edge_types[0]);
    for (std::size_t h = 0; h < holes; ++h) read_ring(in, what, p.geometry.inners()[h], p.edge_types[1 + h]);
  }
  std::string why;
  if (!is_valid(polygons, &why)) throw ArchiveError(what + " is not a valid typed polygon: " + why);
  return polygons;
}

void write_polygon_map(archive::ByteWriter& out, const PolygonMap& map) {
  out.put<double>(map.options().tile_size_m);
  out.put<double>(map.options().tile_origin_m);
  out.put<std::int64_t>(map.scans_inserted());
  out.put<std::int64_t>(map.failed_tile_updates());
  // Reserved, always 0: once the count of overlays redone with Boost, which
  // none is since issue 16. Kept so maps saved before read as they did.
  out.put<std::int64_t>(0);
  out.put<std::uint64_t>(map.tiles().size());
  for (const auto& [key, tile] : map.tiles()) {
    out.put<std::int32_t>(key.first);
    out.put<std::int32_t>(key.second);
    write_typed_multipolygon(out, tile->free);
    write_typed_multipolygon(out, tile->obstacles);
  }
}

PolygonMap read_polygon_map(archive::ByteReader& in, const PolygonMapOptions& options) {
  const double tile_size = in.get<double>(), tile_origin = in.get<double>();
  if (tile_size != options.tile_size_m || tile_origin != options.tile_origin_m)
    throw ArchiveError("the map was saved with tiles of " + std::to_string(tile_size) + " m at " +
                       std::to_string(tile_origin) + " m, the configuration has " +
                       std::to_string(options.tile_size_m) + " m at " + std::to_string(options.tile_origin_m) + " m");
  const auto scans = in.get<std::int64_t>(), failed = in.get<std::int64_t>();
  (void)in.get<std::int64_t>();  // reserved (see write_polygon_map)
  PolygonMap map(options);
  map.restore_counters(scans, failed);
  const auto tiles = in.get_count(2 * sizeof(std::int32_t) + 2 * sizeof(std::uint64_t));
  for (std::uint64_t i = 0; i < tiles; ++i) {
    const PolygonMap::TileKey key{in.get<std::int32_t>(), in.get<std::int32_t>()};
    if (map.tiles().count(key)) throw ArchiveError("tile (" + std::to_string(key.first) + ", " +
                                                   std::to_string(key.second) + ") saved twice");
    const std::string name = "tile (" + std::to_string(key.first) + ", " + std::to_string(key.second) + ")";
    auto free = read_typed_multipolygon(in, name + " free layer");
    auto obstacles = read_typed_multipolygon(in, name + " obstacle layer");
    map.restore_tile(key, std::move(free), std::move(obstacles));
  }
  return map;
}

}  // namespace pex::mapping
