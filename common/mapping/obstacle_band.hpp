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

// Each open chain shortened at both ends by end_trim_m, but by at most a
// quarter of its length (a short chain, a pole, keeps its middle). Closed
// chains are left whole.
void trim_chain_ends(Chains& chains, double end_trim_m);

// The band of a scan: direct_obstacle_band, else Boost's buffer of the chains
// (closed chains, folds: Boost's buffer is the simpler tool there), of the
// chains trimmed by end_trim_m first. Valid, or empty with the reason in
// *why if given.
//
// Why trim: an open chain ends where the laser saw past the wall (a door's
// jamb) or where the wall went out of sight. The map's band is the union of
// every scan's, so each jamb is banded as far into the opening as the worst
// pose error of all the scans that saw it: doors of 1 m were mapped 0.5-0.7 m
// wide and closed in the configuration space as scans accumulated (office,
// intel missions, docs/exploration.md). The wall itself stays sealed where
// its chain is whole; a trimmed end leaves the wall's last centimetres to the
// free map's edges, far narrower than any robot. The cost: a box's corner
// seen one face at a time loses its band too, so a scan placed a little
// off leaves free space inside the corner (office with 0.1 m: every door
// open, but box corners touched 3 and 6 times; docs/exploration.md). Off
// (0) in the shipped configs.
MultiPolygon obstacle_band(const TypedPolygon& scan, double inner_m, double outer_m,
                           std::string* why = nullptr, double end_trim_m = 0.0);

}  // namespace pex::mapping
