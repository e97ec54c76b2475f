#pragma once
// Reads a fuzz input as a stream of small values (LLVM's FuzzedDataProvider
// does the same but comes with clang only; the corpus replay is built by GCC).
// Past the end every read returns 0 / empty, so any input is a valid stream.
#include <cstdint>
#include <cstring>
#include <string_view>

namespace pex::fuzz {

class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  bool empty() const { return pos_ >= size_; }
  std::size_t left() const { return size_ - pos_; }

  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(byte() | (byte() << 8)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16); }
  std::uint64_t u64() { return static_cast<std::uint64_t>(u32()) | (static_cast<std::uint64_t>(u32()) << 32); }
  // Any double, NaN and infinities included (its 8 bytes as they come).
  double any_double() {
    const std::uint64_t bits = u64();
    double d;
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
  // `n` bytes (fewer at the end).
  std::string_view bytes(std::size_t n) {
    if (n > left()) n = left();
    std::string_view out(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return out;
  }
  std::string_view rest() { return bytes(left()); }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace pex::fuzz
