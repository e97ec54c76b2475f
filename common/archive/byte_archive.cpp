#include "archive/byte_archive.hpp"

namespace pex::archive {

std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string seal(std::string_view magic, std::uint32_t version, std::string_view payload) {
  if (magic.size() != 8) throw std::invalid_argument("archive magic must be 8 characters");
  ByteWriter w;
  std::string out(magic);
  w.put<std::uint32_t>(version);
  w.put<std::uint64_t>(payload.size());
  out += w.bytes();
  out.append(payload.data(), payload.size());
  ByteWriter sum;
  sum.put<std::uint64_t>(fnv1a64(out));
  out += sum.bytes();
  return out;
}

std::string unseal(std::string_view magic, std::uint32_t version, std::string_view archive) {
  constexpr std::size_t kHeader = 8 + 4 + 8, kTrailer = 8;
  if (archive.size() < kHeader + kTrailer)
    throw ArchiveError("cut short: " + std::to_string(archive.size()) + " bytes, not even a header");
  if (archive.substr(0, 8) != magic)
    throw ArchiveError("not a " + std::string(magic) + " archive (it starts with \"" +
                       std::string(archive.substr(0, 8)) + "\")");
  ByteReader header(archive.substr(8, 12));
  const auto got_version = header.get<std::uint32_t>();
  const auto size = header.get<std::uint64_t>();
  if (got_version != version)
    throw ArchiveError("format version " + std::to_string(got_version) + ", this build reads " +
                       std::to_string(version));
  if (size != archive.size() - kHeader - kTrailer)
    throw ArchiveError("cut short or padded: the header says " + std::to_string(size) + " payload bytes, there are " +
                       std::to_string(archive.size() - kHeader - kTrailer));
  ByteReader trailer(archive.substr(archive.size() - kTrailer));
  if (trailer.get<std::uint64_t>() != fnv1a64(archive.substr(0, archive.size() - kTrailer)))
    throw ArchiveError("checksum mismatch: the file is damaged");
  return std::string(archive.substr(kHeader, size));
}

}  // namespace pex::archive
