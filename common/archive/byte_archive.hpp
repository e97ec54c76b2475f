#pragma once
// Binary checkpoints of algorithm state (SLAM filter, particle maps): a byte
// string, not a file, so the algorithms stay free of I/O (the daemon writes it
// with runtime::write_file_atomically).
//
// Layout of a sealed archive: magic (8 bytes) | format version (u32) |
// payload size (u64) | payload | FNV-1a 64 of everything before it (u64).
// Numbers are little-endian, fixed width; doubles and floats are their IEEE
// bit patterns, so a restored state is bit-identical (same log and seed, same
// map, also across a restart). A file that is cut short, bit-flipped, of
// another kind or another version is refused with a reason, never half read.
#include <bit>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

namespace pex::archive {

// Thrown by ByteReader and unseal() for anything but a well-formed archive.
class ArchiveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ByteWriter {
 public:
  template <typename T>
    requires std::is_arithmetic_v<T>
  void put(T value) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    out_.append(reinterpret_cast<const char*>(bytes), sizeof(T));
  }
  void put_bool(bool value) { put<std::uint8_t>(value ? 1 : 0); }
  void put_string(std::string_view text) {
    put<std::uint64_t>(text.size());
    out_.append(text.data(), text.size());
  }
  const std::string& bytes() const { return out_; }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

class ByteReader {
 public:
  explicit ByteReader(std::string_view bytes) : in_(bytes) {}

  template <typename T>
    requires std::is_arithmetic_v<T>
  T get() {
    need(sizeof(T));
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, in_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    if constexpr (std::endian::native == std::endian::big)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }
  bool get_bool() {
    const auto v = get<std::uint8_t>();
    if (v > 1) throw ArchiveError("a boolean byte is " + std::to_string(v));
    return v == 1;
  }
  std::string get_string() {
    const auto size = get<std::uint64_t>();
    need(size);
    std::string text(in_.substr(at_, size));
    at_ += size;
    return text;
  }
  // A count of elements of at least `min_element_bytes` each that must fit in
  // what is left: a corrupt count is refused before anything is allocated.
  std::uint64_t get_count(std::size_t min_element_bytes) {
    const auto n = get<std::uint64_t>();
    if (min_element_bytes > 0 && n > remaining() / min_element_bytes)
      throw ArchiveError("a count of " + std::to_string(n) + " does not fit in the " + std::to_string(remaining()) +
                         " bytes left");
    return n;
  }
  std::size_t remaining() const { return in_.size() - at_; }
  // Throws unless every byte was read (a payload longer than its reader expects
  // is as wrong as a shorter one).
  void expect_end() const {
    if (remaining() != 0) throw ArchiveError(std::to_string(remaining()) + " bytes left over");
  }

 private:
  void need(std::uint64_t n) const {
    if (n > remaining())
      throw ArchiveError("cut short: " + std::to_string(n) + " bytes wanted at byte " + std::to_string(at_) + ", " +
                         std::to_string(remaining()) + " left");
  }
  std::string_view in_;
  std::size_t at_ = 0;
};

std::uint64_t fnv1a64(std::string_view bytes);

// magic: exactly 8 characters naming the kind of state ("PEXSLAM1").
std::string seal(std::string_view magic, std::uint32_t version, std::string_view payload);
// The payload of a sealed archive of this magic and version; ArchiveError
// saying why otherwise.
std::string unseal(std::string_view magic, std::uint32_t version, std::string_view archive);

}  // namespace pex::archive
