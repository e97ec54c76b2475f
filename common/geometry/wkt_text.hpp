#pragma once
// Reading the hand-written WKT files of worlds and keep-out zones: a line's
// text without its surrounding blanks, its leading keyword, the bound on
// coordinates that catches a typo'd exponent, and the check that a polygon's
// rings are closed. Header-only, no I/O.
#include <cctype>
#include <cmath>
#include <string>
#include <string_view>

namespace pex::geometry {

// Coordinates beyond this (m) are a mistake in a building's file.
inline constexpr double kMaxFileCoordinateM = 1e5;

// A file's coordinate pair is finite and within kMaxFileCoordinateM.
inline bool file_coordinates_ok(double x, double y) {
  return std::isfinite(x) && std::isfinite(y) && std::abs(x) <= kMaxFileCoordinateM &&
         std::abs(y) <= kMaxFileCoordinateM;
}
inline constexpr const char* kBadFileCoordinate = "coordinate not finite or beyond 1e5 m";

// "" when every ring of `polygon` (as Boost.Geometry reads a POLYGON) is
// closed, its last point its first and 4 points at least; else what is
// wrong. Boost's read_wkt does not close a ring, and one left open would
// drop an edge nobody meant to drop.
template <class Polygon>
std::string unclosed_ring(const Polygon& polygon) {
  auto closed = [](const auto& ring) {
    return ring.size() >= 4 && ring.front().x() == ring.back().x() && ring.front().y() == ring.back().y();
  };
  if (!closed(polygon.outer())) return "POLYGON ring not closed (its last point must be its first, 4 points at least)";
  for (const auto& inner : polygon.inners())
    if (!closed(inner)) return "POLYGON hole not closed (its last point must be its first, 4 points at least)";
  return "";
}

// `s` without leading and trailing blanks (spaces, tabs, a CR).
inline std::string trim_blanks(std::string_view s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  const auto end = s.find_last_not_of(" \t\r");
  return std::string(s.substr(begin, end - begin + 1));
}

// The letters `s` starts with, upper-cased ("linestring(0 0" -> "LINESTRING").
inline std::string leading_keyword(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (!std::isalpha(static_cast<unsigned char>(c))) break;
    out.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  }
  return out;
}

}  // namespace pex::geometry
