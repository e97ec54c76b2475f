#pragma once
// The obstacle band of a scan polygon (paper, section 3.3): each maximal chain
// of obstacle edges widened asymmetrically, `inner_m` into the free side
// (left of a counter-clockwise ring) and `outer_m` beyond the wall, with flat
// ends and round joins (8 points a circle).
#include <optional>
#include <string>

#include "mapping/typed_polygon.hpp"

namespace pex::mapping {

// The maximal chains of obstacle edges of a scan polygon (what the band covers).
using Chain = bg::model::linestring<Point>;
using Chains = bg::model::multi_linestring<Chain>;
Chains obstacle_chains(const TypedPolygon& scan);

// The band built chain by chain (right offset by outer_m, left by inner_m,
// round outer joins, flat ends): nullopt unless every chain is open, every
// join can be built by meeting offset lines and every chain's band is
// clearly valid; bands that overlap are united (typed_union).
std::optional<MultiPolygon> direct_obstacle_band(const Chains& chains, double inner_m, double outer_m);

// The band of a scan: direct_obstacle_band, else Boost's buffer of the chains
// (closed chains, folds: Boost's buffer is the simpler tool there). Valid, or
// empty with the reason in *why if given.
MultiPolygon obstacle_band(const TypedPolygon& scan, double inner_m, double outer_m,
                           std::string* why = nullptr);

}  // namespace pex::mapping
