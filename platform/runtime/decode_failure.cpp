#include <cinttypes>
#include <cstdio>
#include <string>

#include "runtime/node.hpp"

namespace pex::runtime {

std::string decode_failure(const void* data, int size, int used, int64_t hash, const char* type_name) {
  const std::string type(type_name);
  if (used >= 0)
    return "a " + type + " of " + std::to_string(used) + " bytes followed by " + std::to_string(size - used) +
           " more";
  if (size < 8) return std::to_string(size) + " bytes, too short for a " + type;
  // Every LCM message opens with its type's fingerprint, big-endian.
  const auto* b = static_cast<const uint8_t*>(data);
  uint64_t got = 0;
  for (int i = 0; i < 8; ++i) got = (got << 8) | b[i];
  if (got != static_cast<uint64_t>(hash)) {
    char text[80];
    std::snprintf(text, sizeof text, " (fingerprint %016" PRIx64 ", not %016" PRIx64 ")", got,
                  static_cast<uint64_t>(hash));
    return std::to_string(size) + " bytes that are not a " + type + text;
  }
  return std::to_string(size) + " bytes that do not decode as " + type +
         ": cut short, or an array count or string length beyond the bytes left";
}

}  // namespace pex::runtime
