// Bounded decoding (issue 12): a message can make a decoder allocate no more
// than a small multiple of its size. lcm-gen's decoders sized every array from
// the count in the packet before looking at the bytes left; the build now
// patches them (cmake/PexLcmBoundedDecode.cmake). This binary counts every
// allocation with its own operator new, so it is a test binary of its own.
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <new>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/mission_cmd_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/sim_fault_t.hpp>
#include <pex/slam_update_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include "runtime/channels.hpp"
#include "runtime/log_capture.hpp"
#include "runtime/node.hpp"

namespace {

// Allocation count of the decode being measured (this thread only).
thread_local bool t_counting = false;
thread_local size_t t_bytes = 0;    // all bytes asked for while counting
thread_local size_t t_largest = 0;  // the largest single request
// Without the bound the hostile counts ask for up to 189 GB at once; such a
// request fails here (std::bad_alloc, as it would on a small robot computer)
// instead of paging in gigabytes while the test runs.
constexpr size_t kRefuseAbove = size_t{64} << 20;

void* allocate(size_t n) {
  if (t_counting) {
    t_bytes += n;
    t_largest = std::max(t_largest, n);
    if (n > kRefuseAbove) throw std::bad_alloc();
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(size_t n) { return allocate(n); }
void* operator new[](size_t n) { return allocate(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

namespace {

constexpr int kPacketBytes = 173;  // the packet

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

struct Decoded {
  int result = 0;
  bool threw = false;
  std::string what;
  size_t allocated = 0;  // bytes asked for during decode()
  size_t largest = 0;
  std::vector<uint8_t> reencoded;  // when it decoded
};

template <class Msg>
Decoded decode_counting(const std::vector<uint8_t>& bytes) {
  Decoded d;
  Msg msg{};
  t_bytes = t_largest = 0;
  t_counting = true;
  try {
    d.result = msg.decode(bytes.data(), 0, static_cast<int>(bytes.size()));
  } catch (const std::exception& e) {
    d.threw = true;
    d.what = e.what();
  }
  t_counting = false;
  d.allocated = t_bytes;
  d.largest = t_largest;
  if (!d.threw && d.result == static_cast<int>(bytes.size())) d.reencoded = encode(msg);
  return d;
}

// One count (or string length) field of one type: `make(n)` is a valid
// message with n elements in that array (or n characters in that string),
// every other array empty.
struct Field {
  std::string name;
  std::function<std::vector<uint8_t>(int n)> encode_with;
  std::function<Decoded(const std::vector<uint8_t>&)> decode;
};

template <class Msg>
Field field(std::string name, std::function<Msg(int)> make) {
  return {std::move(name), [make](int n) { return encode(make(n)); },
          [](const std::vector<uint8_t>& b) { return decode_counting<Msg>(b); }};
}

pex::laser_scan_t scan(int nranges, int nintensities) {
  pex::laser_scan_t s{};
  s.utime = 1;
  s.angle_increment = 0.01f;
  s.range_max = 20;
  s.nranges = nranges;
  s.ranges.assign(static_cast<size_t>(nranges), 1.5f);
  s.nintensities = nintensities;
  s.intensities.assign(static_cast<size_t>(nintensities), 7.0f);
  return s;
}

pex::polygon_ring_t ring(int nvertices) {
  pex::polygon_ring_t r{};
  r.nvertices = nvertices;
  for (int i = 0; i < nvertices; ++i) {
    r.x.push_back(i);
    r.y.push_back(i * i);
    r.edge_type.push_back(static_cast<int8_t>(i % 2));
  }
  return r;
}

pex::polygon_map_t map(int nrings, int nvertices) {
  pex::polygon_map_t m{};
  m.utime = 3;
  m.nrings = nrings;
  for (int i = 0; i < nrings; ++i) m.rings.push_back(ring(nvertices));
  return m;
}

pex::slam_update_t update(int nparticles) {
  pex::slam_update_t u{};
  u.utime = 2;
  u.epoch = 1;
  u.nparticles = nparticles;
  for (int i = 0; i < nparticles; ++i) {
    pex::particle_t p{};
    p.x = i;
    p.log_weight = -1;
    p.parent = i;
    u.particles.push_back(p);
  }
  return u;
}

pex::explore_state_t explore(int npath, int nfrontiers) {
  pex::explore_state_t e{};
  e.utime = 4;
  e.status = "moving";
  e.strategy = "greedy";
  e.npath = npath;
  e.path_x.assign(static_cast<size_t>(npath), 1.0);
  e.path_y.assign(static_cast<size_t>(npath), 2.0);
  e.nfrontiers = nfrontiers;
  e.frontier_x.assign(static_cast<size_t>(nfrontiers), 3.0);
  e.frontier_y.assign(static_cast<size_t>(nfrontiers), 4.0);
  e.frontier_reason.assign(static_cast<size_t>(nfrontiers), 1);
  return e;
}

pex::daemon_status_t status(int ncounters, const std::string& name = "slam") {
  pex::daemon_status_t s{};
  s.utime = 5;
  s.name = name;
  s.last_error = "";
  s.ncounters = ncounters;
  for (int i = 0; i < ncounters; ++i) {
    s.counter_names.push_back("counter_" + std::to_string(i));
    s.counter_values.push_back(i);
  }
  return s;
}

// Every array count and string length of the types the daemons subscribe to
// (and DAEMON_STATUS, which the tools read).
std::vector<Field> all_fields() {
  return {
      field<pex::laser_scan_t>("laser_scan_t.nranges", [](int n) { return scan(n, 0); }),
      field<pex::laser_scan_t>("laser_scan_t.nintensities", [](int n) { return scan(0, n); }),
      field<pex::slam_update_t>("slam_update_t.nparticles", [](int n) { return update(n); }),
      field<pex::polygon_map_t>("polygon_map_t.nrings", [](int n) { return map(n, 0); }),
      field<pex::polygon_map_t>("polygon_map_t.rings[0].nvertices", [](int n) { return map(1, n); }),
      field<pex::explore_state_t>("explore_state_t.npath", [](int n) { return explore(n, 0); }),
      field<pex::explore_state_t>("explore_state_t.nfrontiers", [](int n) { return explore(0, n); }),
      field<pex::daemon_status_t>("daemon_status_t.ncounters", [](int n) { return status(n); }),
      field<pex::daemon_status_t>("daemon_status_t.name", [](int n) { return status(0, std::string(n, 'x')); }),
      field<pex::velocity_cmd_t>("velocity_cmd_t.source",
                                 [](int n) {
                                   pex::velocity_cmd_t c{};
                                   c.source = std::string(n, 's');
                                   return c;
                                 }),
      field<pex::mission_cmd_t>("mission_cmd_t.source",
                                [](int n) {
                                  pex::mission_cmd_t c{};
                                  c.command = pex::mission_cmd_t::CMD_START;
                                  c.source = std::string(n, 's');
                                  return c;
                                }),
      field<pex::sim_fault_t>("sim_fault_t.source",
                              [](int n) {
                                pex::sim_fault_t f{};
                                f.source = std::string(n, 's');
                                return f;
                              }),
  };
}

// The field's place in the encoding: the two messages with 0 and 1 elements
// first differ in the last byte of the big-endian int32 that counts them.
size_t count_offset(const Field& f) {
  const auto a = f.encode_with(0), b = f.encode_with(1);
  const auto diff = std::mismatch(a.begin(), a.end(), b.begin()).first - a.begin();
  return static_cast<size_t>(diff) - 3;
}

// The message with no elements, its count field saying `count`, padded with
// zeros to the 173 bytes.
std::vector<uint8_t> hostile(const Field& f, int32_t count) {
  auto bytes = f.encode_with(0);
  const size_t at = count_offset(f);
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<uint8_t>(static_cast<uint32_t>(count) >> (24 - 8 * i));
  if (bytes.size() < kPacketBytes) bytes.resize(kPacketBytes, 0);
  return bytes;
}

// What the issue allows: a small multiple of the message's size plus a fixed
// amount. k = 10 covers our types' worst, an array of empty polygon rings (9
// encoded bytes, 88 bytes each in memory: docs/channels.md).
constexpr size_t kBytesPerByte = 10;
constexpr size_t kFixedBytes = 1024;
size_t allowed(size_t message_bytes) { return kBytesPerByte * message_bytes + kFixedBytes; }

}  // namespace

TEST(BoundedDecode, HugeOrNegativeCountsFailBeforeAllocating) {
  int packets = 0;
  size_t most = 0;
  for (const Field& f : all_fields()) {
    for (const int32_t count : {INT32_MAX, 10'000'000, 1 << 20, -1, INT32_MIN}) {
      const auto bytes = hostile(f, count);
      ASSERT_EQ(bytes.size(), size_t{kPacketBytes}) << f.name;
      const Decoded d = f.decode(bytes);
      ++packets;
      most = std::max(most, d.allocated);
      EXPECT_FALSE(d.threw) << f.name << " = " << count << ": " << d.what << " (asked for " << d.largest
                            << " bytes at once)";
      EXPECT_LT(d.result, 0) << f.name << " = " << count;
      // "a 173-byte packet cannot cost more than a few KB"
      EXPECT_LE(d.allocated, size_t{4096}) << f.name << " = " << count << ": asked for " << d.largest
                                            << " bytes at once";
    }
  }
  std::cout << packets << " hostile packets of " << kPacketBytes << " bytes: at most " << most
            << " bytes allocated for one\n";
}

TEST(BoundedDecode, ValidMessagesRoundTripUnchanged) {
  const std::vector<std::pair<std::string, std::vector<uint8_t>>> messages = {
      {"scan 1081 beams", encode(scan(1081, 1081))},
      {"map 40 rings", encode(map(40, 25))},
      {"slam update 30 particles", encode(update(30))},
      {"explore state", encode(explore(120, 35))},
      {"daemon status", encode(status(12))},
  };
  const auto decoders = std::vector<std::function<Decoded(const std::vector<uint8_t>&)>>{
      decode_counting<pex::laser_scan_t>, decode_counting<pex::polygon_map_t>, decode_counting<pex::slam_update_t>,
      decode_counting<pex::explore_state_t>, decode_counting<pex::daemon_status_t>};
  for (size_t i = 0; i < messages.size(); ++i) {
    const auto& [name, bytes] = messages[i];
    const Decoded d = decoders[i](bytes);
    EXPECT_EQ(d.result, static_cast<int>(bytes.size())) << name;
    EXPECT_EQ(d.reencoded, bytes) << name;
    EXPECT_LE(d.allocated, allowed(bytes.size())) << name;
  }
  // Every field at the largest count its message's bytes can hold still decodes.
  for (const Field& f : all_fields()) {
    const auto bytes = f.encode_with(500);
    const Decoded d = f.decode(bytes);
    EXPECT_EQ(d.result, static_cast<int>(bytes.size())) << f.name;
    EXPECT_EQ(d.reencoded, bytes) << f.name;
  }
}

// The bound is per byte of the message, whatever its size: the densest valid
// messages (arrays of empty elements) are where memory per encoded byte peaks.
TEST(BoundedDecode, AllocationIsASmallMultipleOfTheMessageSize) {
  const std::vector<std::pair<std::string, Decoded>> cases = {
      {"map of 5000 empty rings", decode_counting<pex::polygon_map_t>(encode(map(5000, 0)))},
      {"status of 5000 empty counter names", decode_counting<pex::daemon_status_t>([] {
         auto s = status(5000);
         for (auto& n : s.counter_names) n.clear();
         return encode(s);
       }())},
      {"update of 5000 particles", decode_counting<pex::slam_update_t>(encode(update(5000)))},
      {"scan of 5000 beams", decode_counting<pex::laser_scan_t>(encode(scan(5000, 0)))},
  };
  for (const auto& [name, d] : cases) {
    ASSERT_GT(d.result, 0) << name;
    const size_t size = static_cast<size_t>(d.result);
    std::cout << name << ": " << size << " bytes -> " << d.allocated << " bytes allocated ("
              << static_cast<double>(d.allocated) / static_cast<double>(size) << " per byte)\n";
    EXPECT_LE(d.allocated, allowed(size)) << name;
  }
}

// Random damage to valid messages: whatever the bytes say, decode() neither
// throws nor allocates beyond the bound.
TEST(BoundedDecode, DamagedMessagesStayWithinTheBound) {
  std::mt19937 rng(12);
  std::vector<std::pair<std::vector<uint8_t>, std::function<Decoded(const std::vector<uint8_t>&)>>> seeds;
  for (const Field& f : all_fields()) seeds.emplace_back(f.encode_with(3), f.decode);
  size_t failures = 0, worst = 0, worst_size = 0;
  for (int round = 0; round < 3000; ++round) {
    for (const auto& [seed, decode] : seeds) {
      auto bytes = seed;
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int i = 0; i < flips; ++i) {
        // Past the fingerprint (a damaged one is refused at once), often a
        // whole byte of 0xff or 0x80 to make counts huge or negative.
        const size_t at = 8 + rng() % (bytes.size() - 8);
        const uint32_t r = rng();
        bytes[at] = r % 3 == 0 ? 0xff : r % 3 == 1 ? 0x80 : static_cast<uint8_t>(r >> 8);
      }
      const Decoded d = decode(bytes);
      if (d.threw || d.allocated > allowed(bytes.size())) {
        if (++failures <= 5)
          ADD_FAILURE() << (d.threw ? "threw " + d.what : "allocated " + std::to_string(d.allocated)) << " for "
                        << bytes.size() << " bytes (largest request " << d.largest << ")";
      }
      if (d.allocated > worst) worst = d.allocated, worst_size = bytes.size();
    }
  }
  std::cout << "most allocated for a damaged message: " << worst << " bytes for " << worst_size << " bytes\n";
  EXPECT_EQ(failures, 0u);
}

// The node counts what fails to decode as rejected input (not as its own
// error), says which channel and why in a rate-limited line, and goes on.
TEST(BoundedDecode, NodeRejectsHostileCountsAndNamesTheChannel) {
  const pex::runtime::LogCapture log;
  pex::runtime::Node node(pex::runtime::NodeOptions{"t", "", true, "", 1.0});
  int calls = 0;
  node.subscribe<pex::laser_scan_t>(pex::runtime::channels::kLidarScan, [&](const pex::laser_scan_t&) { ++calls; });
  const Field nranges = all_fields().front();
  const std::string channel(pex::runtime::channels::kLidarScan);
  int64_t t = 1;
  for (const int32_t count : {-1, INT32_MIN, INT32_MAX}) {
    const auto bytes = hostile(nranges, count);
    node.dispatch(channel, bytes.data(), static_cast<int>(bytes.size()), t++);
  }
  EXPECT_EQ(node.msgs_rejected(), 3);
  EXPECT_EQ(calls, 0);
  const std::string logged = log.text();
  const std::string first_line = logged.substr(0, logged.find('\n'));
  EXPECT_NE(first_line.find(channel), std::string::npos) << first_line;
  EXPECT_NE(first_line.find("count or string length beyond the bytes left"), std::string::npos) << first_line;

  // A flood is logged in a line or two, not a line per packet.
  const auto flood = hostile(nranges, INT32_MAX);
  for (int i = 0; i < 1000; ++i) node.dispatch(channel, flood.data(), static_cast<int>(flood.size()), t++);
  EXPECT_EQ(node.msgs_rejected(), 1003);
  EXPECT_LT(log.lines(), 10) << log.text();

  const auto good = encode(scan(10, 0));
  node.dispatch(channel, good.data(), static_cast<int>(good.size()), t++);
  EXPECT_EQ(calls, 1);
}

// The reason names what is wrong: another type, bytes left over, too few bytes.
TEST(BoundedDecode, TheReasonSaysWhatIsWrong) {
  using pex::runtime::decode_failure;
  const auto hash = pex::laser_scan_t::getHash();
  const char* type = pex::laser_scan_t::getTypeName();
  const auto other = encode(status(0));
  pex::laser_scan_t msg{};
  EXPECT_NE(decode_failure(other.data(), static_cast<int>(other.size()),
                           msg.decode(other.data(), 0, static_cast<int>(other.size())), hash, type)
                .find("that are not a laser_scan_t (fingerprint"),
            std::string::npos);
  auto longer = encode(scan(10, 0));
  const int used = static_cast<int>(longer.size());
  longer.push_back(0);
  EXPECT_EQ(decode_failure(longer.data(), static_cast<int>(longer.size()), used, hash, type),
            "a laser_scan_t of " + std::to_string(used) + " bytes followed by 1 more");
  EXPECT_EQ(decode_failure(longer.data(), 5, -1, hash, type), "5 bytes, too short for a laser_scan_t");
}
