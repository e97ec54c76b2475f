#include "archive/byte_archive.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace pex::archive {
namespace {

TEST(ByteArchive, NumbersComeBackBitForBit) {
  ByteWriter w;
  w.put<double>(-0.0);
  w.put<double>(std::numeric_limits<double>::denorm_min());
  w.put<double>(std::nan(""));
  w.put<float>(1.1f);
  w.put<std::int64_t>(-5);
  w.put<std::uint16_t>(65535);
  w.put_bool(true);
  w.put_string(std::string_view("two\0words", 9));
  ByteReader r(w.bytes());
  const double z = r.get<double>();
  EXPECT_TRUE(z == 0.0 && std::signbit(z));
  EXPECT_EQ(r.get<double>(), std::numeric_limits<double>::denorm_min());
  EXPECT_TRUE(std::isnan(r.get<double>()));
  EXPECT_EQ(r.get<float>(), 1.1f);
  EXPECT_EQ(r.get<std::int64_t>(), -5);
  EXPECT_EQ(r.get<std::uint16_t>(), 65535);
  EXPECT_TRUE(r.get_bool());
  EXPECT_EQ(r.get_string(), std::string("two\0words", 9));
  r.expect_end();
}

TEST(ByteArchive, LittleEndianOnTheWire) {
  ByteWriter w;
  w.put<std::uint32_t>(0x01020304u);
  EXPECT_EQ(w.bytes(), std::string("\x04\x03\x02\x01", 4));
}

TEST(ByteArchive, ReadingPastTheEndThrows) {
  ByteWriter w;
  w.put<std::uint32_t>(7);
  ByteReader r(w.bytes());
  EXPECT_THROW(r.get<std::uint64_t>(), ArchiveError);
}

TEST(ByteArchive, ACountThatCannotFitIsRefusedBeforeAllocating) {
  ByteWriter w;
  w.put<std::uint64_t>(1'000'000'000'000ULL);
  w.put<double>(1.0);
  ByteReader r(w.bytes());
  EXPECT_THROW(r.get_count(sizeof(double)), ArchiveError);
}

TEST(ByteArchive, SealedPayloadRoundTrips) {
  const std::string payload("state\0with zero", 15);
  EXPECT_EQ(unseal("PEXTEST1", 3, seal("PEXTEST1", 3, payload)), payload);
}

TEST(ByteArchive, BrokenArchivesAreRefusedWithAReason) {
  const std::string sealed = seal("PEXTEST1", 3, "0123456789");
  auto why = [](auto&& f) {
    try {
      f();
    } catch (const ArchiveError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(why([&] { unseal("PEXOTHER", 3, sealed); }).find("not a PEXOTHER"), std::string::npos);
  EXPECT_NE(why([&] { unseal("PEXTEST1", 4, sealed); }).find("version 3"), std::string::npos);
  EXPECT_NE(why([&] { unseal("PEXTEST1", 3, sealed.substr(0, sealed.size() - 1)); }).find("cut short"),
            std::string::npos);
  EXPECT_NE(why([&] { unseal("PEXTEST1", 3, sealed.substr(0, 10)); }).find("cut short"), std::string::npos);
  std::string flipped = sealed;
  flipped[22] ^= 0x10;
  EXPECT_NE(why([&] { unseal("PEXTEST1", 3, flipped); }).find("checksum"), std::string::npos);
}

}  // namespace
}  // namespace pex::archive
