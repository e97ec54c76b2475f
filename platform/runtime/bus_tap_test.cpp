#include "runtime/bus_tap.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

using pex::runtime::parse_lcm_packet;
using pex::runtime::parse_udpm_url;

TEST(BusTap, UdpmUrlsGiveGroupAndPort) {
  const auto a = parse_udpm_url("udpm://239.255.76.67:7667?ttl=0");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->group, "239.255.76.67");
  EXPECT_EQ(a->port, 7667);
  const auto b = parse_udpm_url("udpm://239.1.2.3:1234");
  ASSERT_TRUE(b);
  EXPECT_EQ(b->group, "239.1.2.3");
  EXPECT_EQ(b->port, 1234);
  const auto defaults = parse_udpm_url("udpm://");
  ASSERT_TRUE(defaults);
  EXPECT_EQ(defaults->port, 7667);
  EXPECT_FALSE(parse_udpm_url("memq://"));
  EXPECT_FALSE(parse_udpm_url("file:///tmp/x.lcm?mode=r"));
  EXPECT_FALSE(parse_udpm_url("udpm://239.1.2.3:notaport"));
  EXPECT_FALSE(parse_udpm_url("udpm://not-an-address:7667"));
}

TEST(BusTap, AnEmptyUrlIsLcmDefaultUrl) {
  ::setenv("LCM_DEFAULT_URL", "udpm://239.9.9.9:7000?ttl=0", 1);
  const auto a = parse_udpm_url("");
  ::unsetenv("LCM_DEFAULT_URL");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->group, "239.9.9.9");
  EXPECT_EQ(a->port, 7000);
  const auto b = parse_udpm_url("");
  ASSERT_TRUE(b);
  EXPECT_EQ(b->group, "239.255.76.67");
}

TEST(BusTap, ShortLcmPacketsGiveChannelAndPayload) {
  std::vector<std::uint8_t> bytes = {0x4c, 0x43, 0x30, 0x32, 0, 0, 0, 7};
  for (char c : std::string("SIM_CLOCK")) bytes.push_back(static_cast<std::uint8_t>(c));
  bytes.push_back(0);
  bytes.insert(bytes.end(), {1, 2, 3});
  const auto p = parse_lcm_packet(bytes.data(), bytes.size());
  ASSERT_TRUE(p);
  EXPECT_EQ(p->channel, "SIM_CLOCK");
  ASSERT_EQ(p->size, 3u);
  EXPECT_EQ(p->data[0], 1);
  EXPECT_EQ(p->data[2], 3);

  auto fragment = bytes;
  fragment[3] = 0x33;  // "LC03": a fragment of a big message
  EXPECT_FALSE(parse_lcm_packet(fragment.data(), fragment.size()));
  auto unterminated = std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + 12);  // channel without its NUL
  EXPECT_FALSE(parse_lcm_packet(unterminated.data(), unterminated.size()));
  EXPECT_FALSE(parse_lcm_packet(bytes.data(), 5));
}
