#pragma once
// Reading the hand-written WKT files of worlds and keep-out zones: a line's
// text without its surrounding blanks, its leading keyword, and the bound on
// coordinates that catches a typo'd exponent. Header-only, no I/O.
#include <cctype>
#include <string>
#include <string_view>

namespace pex::geometry {

// Coordinates beyond this (m) are a mistake in a building's file.
inline constexpr double kMaxFileCoordinateM = 1e5;

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
