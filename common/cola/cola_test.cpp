#include "cola/cola.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace pex::cola {
namespace {

// A 21-value scan telegram in the layout of SICK's telegram listing (values
// typed by hand from the documented field order: version 1, device 1, serial,
// status 0 0, telegram counter, scan counter, time since start-up, time of
// transmission, inputs 0 0, outputs 7 0, reserved 0, 50 Hz, measurement
// frequency, no encoders, one 16-bit channel DIST1 scale 1.0 offset 0 starting
// at +10 deg in 0.5 deg steps, then no 8-bit channel, no position, no name, no
// comment, no time, no event).
const char* kRecordedBody =
    "sRA LMDscandata 1 1 89A27F 0 0 343 347 27477BA9 2747813B 0 0 7 0 0 1388 168 0 1 DIST1 "
    "3F800000 00000000 186A0 1388 15 8A1 8A5 8AB 8AC 8A6 8AC 8B6 8C8 8C2 8C9 8CB 8C4 8E4 8E1 8EB "
    "8E0 8F5 908 8FC 907 906 0 0 0 0 0 0";

ScanData parse_ok(std::string_view body) {
  auto split = split_telegram(body);
  EXPECT_TRUE(std::holds_alternative<Telegram>(split));
  auto scan = parse_scan_data(std::get<Telegram>(split));
  if (auto* e = std::get_if<ParseError>(&scan)) ADD_FAILURE() << e->message;
  return std::get<ScanData>(scan);
}

std::string parse_error(std::string_view body) {
  auto split = split_telegram(body);
  if (auto* e = std::get_if<ParseError>(&split)) return e->message;
  auto scan = parse_scan_data(std::get<Telegram>(split));
  if (auto* e = std::get_if<ParseError>(&scan)) return e->message;
  return "";
}

TEST(ColaRequests, MatchTheTelegramListing) {
  EXPECT_EQ(set_access_mode_request(kUserLevelAuthorizedClient, kPasswordAuthorizedClient),
            "\x02sMN SetAccessMode 03 F4724744\x03");
  EXPECT_EQ(set_scan_config_request(ScanConfig{}), "\x02sMN mLMPsetscancfg +2500 +1 +5000 -450000 +2250000\x03");
  EXPECT_EQ(scan_data_config_request(ScanDataConfig{}),
            "\x02sWN LMDscandatacfg 01 00 1 0 0 00 00 0 0 0 0 +1\x03");
  EXPECT_EQ(output_range_request(ScanConfig{}), "\x02sWN LMPoutputRange 1 1388 FFF92230 225510\x03");
  EXPECT_EQ(scan_output_request(true), "\x02sEN LMDscandata 1\x03");
  EXPECT_EQ(scan_output_request(false), "\x02sEN LMDscandata 0\x03");
  EXPECT_EQ(run_request(), "\x02sMN Run\x03");
  // The LMS5xx operating instructions' example, "Read contamination level".
  EXPECT_EQ(contamination_state_request(), "\x02sRN LCMstate\x03");
}

TEST(ColaContamination, TheLevelOfAnLcmStateAnswerAndNothingElse) {
  auto level_of = [](std::string_view body) {
    return contamination_level(std::get<Telegram>(split_telegram(body)));
  };
  EXPECT_EQ(level_of("sRA LCMstate 0"), ContaminationLevel::kNone);
  EXPECT_EQ(level_of("sRA LCMstate 1"), ContaminationLevel::kWarning);
  EXPECT_EQ(level_of("sRA LCMstate 2"), ContaminationLevel::kError);
  EXPECT_EQ(level_of("sRA LCMstate 3"), ContaminationLevel::kSeriousError);
  EXPECT_EQ(level_of("sRA LCMstate 4"), std::nullopt);
  EXPECT_EQ(level_of("sRA LCMstate"), std::nullopt);
  EXPECT_EQ(level_of("sRA LCMstate 1 1"), std::nullopt);
  EXPECT_EQ(level_of("sRA STlms 1"), std::nullopt);
  EXPECT_EQ(level_of("sAN LCMstate 1"), std::nullopt);
}

TEST(ColaNumbers, HexDecimalAndReals) {
  EXPECT_EQ(parse_uint("1388", 0xFFFF), 5000u);
  EXPECT_EQ(parse_uint("+2500", 0xFFFF), 2500u);
  EXPECT_FALSE(parse_uint("10000", 0xFFFF).has_value());  // 65536 > max
  EXPECT_FALSE(parse_uint("12G", 0xFFFF).has_value());
  EXPECT_FALSE(parse_uint("", 0xFFFF).has_value());
  EXPECT_FALSE(parse_uint("-5", 0xFFFF).has_value());
  EXPECT_EQ(parse_int32("FFF92230"), -450000);
  EXPECT_EQ(parse_int32("-450000"), -450000);
  EXPECT_EQ(parse_int32("225510"), 2250000);
  EXPECT_FLOAT_EQ(*parse_real("3F800000"), 1.0f);
  EXPECT_FLOAT_EQ(*parse_real("40000000"), 2.0f);
  EXPECT_FALSE(parse_real("7FC00000").has_value());  // NaN scale is refused
  EXPECT_FALSE(parse_real("3F8000").has_value());
  EXPECT_EQ(hex(0), "0");
  EXPECT_EQ(hex(0x8A1), "8A1");
  EXPECT_EQ(hex_int32(-450000), "FFF92230");
}

// The encoder writes the recorded telegram back character for character: its
// numbers as the laser writes them (hex without leading zeros, reals as 8 hex
// digits, 3F800000 and 00000000 here).
TEST(ColaScanData, EncodesTheRecordedTelegramBackToItsText) {
  EXPECT_EQ(encode_scan_data(parse_ok(kRecordedBody), /*as_poll_answer=*/true), std::string("\x02") + kRecordedBody + "\x03");
}

TEST(ColaScanData, ParsesTheRecordedTelegramFieldByField) {
  ScanData s = parse_ok(kRecordedBody);
  EXPECT_EQ(s.version, 1);
  EXPECT_EQ(s.device_number, 1);
  EXPECT_EQ(s.serial_number, 0x89A27Fu);
  EXPECT_EQ(s.telegram_counter, 0x343);
  EXPECT_EQ(s.scan_counter, 0x347);
  EXPECT_EQ(s.time_since_startup_us, 0x27477BA9u);
  EXPECT_EQ(s.time_of_transmission_us, 0x2747813Bu);
  EXPECT_EQ(s.digital_outputs[0], 7);
  EXPECT_EQ(s.scan_frequency_centihz, 5000u);  // 0x1388 = 50 Hz
  EXPECT_EQ(s.measurement_frequency_100hz, 0x168u);
  ASSERT_EQ(s.channels16.size(), 1u);
  EXPECT_TRUE(s.channels8.empty());
  const Channel* dist = s.find_channel("DIST1");
  ASSERT_NE(dist, nullptr);
  EXPECT_EQ(dist->start_angle_1e4deg, 100000);  // +10 deg
  EXPECT_EQ(dist->angular_step_1e4deg, 5000);
  ASSERT_EQ(dist->data.size(), 21u);
  auto ranges = distances_m(*dist);
  EXPECT_FLOAT_EQ(ranges.front(), 2.209f);  // 0x8A1 mm
  EXPECT_FLOAT_EQ(ranges.back(), 2.310f);   // 0x906 mm
  EXPECT_FALSE(s.date_time.has_value());
  EXPECT_EQ(s.find_channel("RSSI1"), nullptr);
}

TEST(ColaScanData, ReservedDistancesAreNoReturnAndScaleApplies) {
  Channel c;
  c.scale_factor = 2.0f;
  c.scale_offset = 0.0f;
  c.data = {0, 1, 15, 16, 1000};
  auto r = distances_m(c);
  EXPECT_TRUE(std::isnan(r[0]));
  EXPECT_TRUE(std::isnan(r[1]));
  EXPECT_TRUE(std::isnan(r[2]));
  EXPECT_FLOAT_EQ(r[3], 0.032f);
  EXPECT_FLOAT_EQ(r[4], 2.0f);
}

ScanData lms111_scan(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> dist(0, 20000), rssi(0, 255);
  ScanData s;
  s.serial_number = 0x1234567;
  s.telegram_counter = 0xFFFF;
  s.scan_counter = 17;
  s.time_since_startup_us = 0xFFFFFF00u;
  s.time_of_transmission_us = 0x10u;
  s.scan_frequency_centihz = 2500;
  s.measurement_frequency_100hz = 0x168;
  Channel d{"DIST1", 1.0f, 0.0f, -450000, 5000, {}};
  Channel r{"RSSI1", 1.0f, 0.0f, -450000, 5000, {}};
  for (int i = 0; i < 541; ++i) {
    d.data.push_back(static_cast<std::uint16_t>(dist(rng)));
    r.data.push_back(static_cast<std::uint16_t>(rssi(rng)));
  }
  s.channels16.push_back(d);
  s.channels8.push_back(r);
  return s;
}

TEST(ColaScanData, EncoderRoundTripsThroughTheParser) {
  ScanData s = lms111_scan(7);
  s.device_name = "LMS111 sim";
  s.comment = "x";
  s.encoders.push_back({123456, 42});
  s.has_position = true;
  s.position[0] = 1.5f;
  s.rotation_type = 2;
  s.date_time = DeviceDateTime{2026, 11, 22, 20, 30, 59, 999999};
  std::string bytes = encode_scan_data(s);
  ASSERT_EQ(bytes.front(), kStx);
  ASSERT_EQ(bytes.back(), kEtx);
  ScanData back = parse_ok(std::string_view(bytes).substr(1, bytes.size() - 2));
  EXPECT_EQ(back.serial_number, s.serial_number);
  EXPECT_EQ(back.telegram_counter, s.telegram_counter);
  EXPECT_EQ(back.time_since_startup_us, s.time_since_startup_us);
  EXPECT_EQ(back.channels16[0].data, s.channels16[0].data);
  EXPECT_EQ(back.channels8[0].data, s.channels8[0].data);
  EXPECT_EQ(back.channels16[0].start_angle_1e4deg, -450000);
  EXPECT_EQ(back.device_name, "LMS111 sim");
  EXPECT_EQ(back.comment, "x");
  ASSERT_EQ(back.encoders.size(), 1u);
  EXPECT_EQ(back.encoders[0].position, 123456u);
  EXPECT_TRUE(back.has_position);
  EXPECT_FLOAT_EQ(back.position[0], 1.5f);
  EXPECT_EQ(back.rotation_type, 2);
  ASSERT_TRUE(back.date_time.has_value());
  EXPECT_EQ(back.date_time->microsecond, 999999u);
  EXPECT_EQ(back.date_time->year, 2026);
}

TEST(ColaScanData, RejectsMalformedTelegramsWithTheField) {
  std::string good = kRecordedBody;
  EXPECT_EQ(parse_error(good), "");
  // Truncated: the last value and the trailing flags are missing.
  EXPECT_NE(parse_error(good.substr(0, good.size() - 16)).find("ends early"), std::string::npos);
  // A count larger than the data present.
  std::string more = good;
  more.replace(more.find(" 15 8A1"), 7, " 16 8A1");
  EXPECT_NE(parse_error(more), "");
  // A count beyond the limit.
  std::string huge = good;
  huge.replace(huge.find(" 15 8A1"), 7, " FFFF 8A1");
  EXPECT_NE(parse_error(huge).find("number of data"), std::string::npos);
  // A non-hex value.
  std::string bad_value = good;
  bad_value.replace(bad_value.find("8AB"), 3, "8XB");
  EXPECT_NE(parse_error(bad_value).find("data"), std::string::npos);
  // Left-over fields.
  EXPECT_NE(parse_error(good + " 0").find("left over"), std::string::npos);
  // NaN scale factor.
  std::string nan_scale = good;
  nan_scale.replace(nan_scale.find("3F800000"), 8, "7FC00000");
  EXPECT_NE(parse_error(nan_scale).find("scale factor"), std::string::npos);
  // Double space, non-printable bytes, bad type.
  EXPECT_NE(parse_error("sRA  LMDscandata 1"), "");
  EXPECT_NE(parse_error(std::string("sRA LMDscandata 1\x01")), "");
  EXPECT_NE(parse_error("xyz LMDscandata"), "");
  EXPECT_NE(parse_error(""), "");
  // Too many channels.
  std::string channels = good;
  channels.replace(channels.find(" 0 1 DIST1"), 10, " 0 9 DIST1");
  EXPECT_NE(parse_error(channels).find("channels"), std::string::npos);
  // A value above 8 bits in an 8-bit channel.
  ScanData s = lms111_scan(1);
  s.channels8[0].data[3] = 256;
  std::string bytes = encode_scan_data(s);
  EXPECT_NE(parse_error(std::string_view(bytes).substr(1, bytes.size() - 2)), "");
}

TEST(ColaFramer, PartialReadsSeveralTelegramsAndGarbage) {
  std::string a = encode_reply("sAN", "SetAccessMode", {"1"});
  std::string b = encode_scan_data(lms111_scan(3));
  std::string c = encode_reply("sEA", "LMDscandata", {"1"});
  std::string stream = "junk" + a + b + "\r\n" + c;
  // Feed in every chunk size from 1 to 37 bytes: the result must not depend on it.
  for (std::size_t chunk = 1; chunk <= 37; chunk += 6) {
    Framer framer;
    std::vector<std::string> bodies;
    for (std::size_t i = 0; i < stream.size(); i += chunk) {
      for (auto& body : framer.push(std::string_view(stream).substr(i, chunk))) bodies.push_back(body);
    }
    ASSERT_EQ(bodies.size(), 3u) << "chunk " << chunk;
    EXPECT_EQ(bodies[0], "sAN SetAccessMode 1");
    EXPECT_EQ(bodies[1], b.substr(1, b.size() - 2));
    EXPECT_EQ(framer.counters().skipped_bytes, 6u);
    EXPECT_EQ(framer.counters().truncated, 0u);
  }
}

TEST(ColaFramer, TruncatedAndOversizeTelegramsAreDroppedAndCounted) {
  Framer framer(Framer::Options{64});
  std::string stream = std::string("\x02sSN LMDscandata 1 1 2") +  // cut off by the next STX
                       "\x02sAN Run 1\x03" + "\x02" + std::string(200, 'A') + "\x03" +
                       "\x02sAN Run 1\x03";
  auto bodies = framer.push(stream);
  ASSERT_EQ(bodies.size(), 2u);
  EXPECT_EQ(bodies[0], "sAN Run 1");
  EXPECT_EQ(bodies[1], "sAN Run 1");
  EXPECT_EQ(framer.counters().truncated, 1u);
  EXPECT_EQ(framer.counters().oversize, 1u);
}

TEST(ColaStreamParser, ScansRepliesAndErrors) {
  StreamParser parser;
  ScanData s = lms111_scan(11);
  std::string bytes = encode_reply("sEA", "LMDscandata", {"1"}) + encode_scan_data(s) +
                      frame("sSN LMDscandata 1 1 ZZ") + encode_reply("sFA", "", {"5"}) +
                      encode_scan_data(s);
  // deliver in two uneven reads
  auto events = parser.push(std::string_view(bytes).substr(0, 1000));
  auto rest = parser.push(std::string_view(bytes).substr(1000));
  events.insert(events.end(), rest.begin(), rest.end());
  ASSERT_EQ(events.size(), 5u);
  EXPECT_TRUE(std::holds_alternative<ReplyEvent>(events[0]));
  ASSERT_TRUE(std::holds_alternative<ScanEvent>(events[1]));
  EXPECT_EQ(std::get<ScanEvent>(events[1]).scan.channels16[0].data.size(), 541u);
  EXPECT_TRUE(std::holds_alternative<ErrorEvent>(events[2]));
  ASSERT_TRUE(std::holds_alternative<ReplyEvent>(events[3]));
  EXPECT_EQ(std::get<ReplyEvent>(events[3]).telegram.type, "sFA");
  EXPECT_EQ(std::get<ReplyEvent>(events[3]).telegram.args, std::vector<std::string>{"5"});
  EXPECT_TRUE(std::holds_alternative<ScanEvent>(events[4]));
  EXPECT_EQ(parser.counters().scans, 2u);
  EXPECT_EQ(parser.counters().malformed, 1u);
  EXPECT_EQ(parser.counters().replies, 2u);
}

TEST(ColaStreamParser, RandomBytesNeverCrash) {
  std::mt19937_64 rng(42);
  std::uniform_int_distribution<int> byte(0, 255);
  StreamParser parser;
  std::string good = encode_scan_data(lms111_scan(5));
  for (int round = 0; round < 200; ++round) {
    std::string noise(static_cast<std::size_t>(byte(rng)), '\0');
    for (char& c : noise) c = static_cast<char>(byte(rng));
    // corrupt a copy of a good telegram at a random place
    std::string corrupt = good;
    corrupt[static_cast<std::size_t>(byte(rng)) * 10 % corrupt.size()] = static_cast<char>(byte(rng));
    parser.push(noise);
    parser.push(corrupt);
  }
  // A clean telegram after all that still comes through.
  parser.reset();
  auto events = parser.push(good);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_TRUE(std::holds_alternative<ScanEvent>(events[0]));
}

}  // namespace
}  // namespace pex::cola

namespace pex::cola {
namespace {

TEST(DeviceClock, LowPercentileDelayOffsetWrapAndRestart) {
  DeviceClock clock;
  const std::int64_t host0 = 1'700'000'000'000'000;
  // Device time starts near the wrap; delays 1, 2, ... 100 ms in a scrambled order.
  std::uint32_t device = 0xFFFF0000u;
  DeviceClock::Mapped m{};
  for (int i = 0; i < 100; ++i) {
    const std::int64_t delay = 1000 * (1 + (i * 37) % 100);
    const std::int64_t device_unwrapped = 0xFFFF0000ll + i * 40'000ll;
    device = static_cast<std::uint32_t>(device_unwrapped);
    m = clock.map(device - 30'000, device, host0 + device_unwrapped + delay);
    EXPECT_EQ(m.device_us, device_unwrapped - 30'000);
  }
  // The tenth-smallest of the 100 delays is 11 ms: the mapped host time is the true one + 11 ms.
  EXPECT_EQ(m.host_us, host0 + m.device_us + 11'000);
  EXPECT_EQ(clock.resets(), 0u);
  EXPECT_EQ(clock.outliers(), 0u);
  // The sensor restarts (a new connection): its clock starts again at 0 and
  // the reader resets the estimate.
  clock.reset();
  m = clock.map(100, 5000, host0 + 50'000'000);
  EXPECT_EQ(m.device_us, 100);
  EXPECT_EQ(m.host_us, host0 + 50'000'000 - 4900);
}

// 250 scans at 25 Hz from device time 1 s, received 1 ms after they were
// sent; returns the host time of device time 0 they give (the offset).
std::int64_t settle(DeviceClock& clock, std::int64_t host0, std::int64_t& device) {
  DeviceClock::Mapped m{};
  for (int i = 0; i < 250; ++i, device += 40'000)
    m = clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device), host0 + device + 1000);
  return m.host_us - m.device_us;
}

// The reader stalled (a loaded computer): the 20 telegrams sent in 0.76 s
// meanwhile are read at once, at one receive time. Each scan keeps its own
// time; starting the estimate afresh on the first of them stamped them all
// with the time they were read.
TEST(DeviceClock, ABacklogReadAtOnceAfterAStallKeepsEachScansOwnTime) {
  DeviceClock clock;
  const std::int64_t host0 = 1'700'000'000'000'000;
  std::int64_t device = 1'000'000;
  ASSERT_EQ(settle(clock, host0, device), host0 + 1000);
  const std::int64_t read_at = host0 + device + 19 * 40'000 + 1000;  // when the last one was sent
  for (int i = 0; i < 20; ++i, device += 40'000) {
    const auto m = clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device), read_at);
    EXPECT_EQ(m.host_us, host0 + 1000 + device - 30'000) << "telegram " << i << " of the backlog";
  }
  // Read 0.52-0.76 s late: outliers; the later ones agree with the estimate.
  EXPECT_EQ(clock.outliers(), 7u);
  EXPECT_EQ(clock.resets(), 0u);
  // And the stream goes on as before.
  const auto m = clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device),
                           host0 + device + 1000);
  EXPECT_EQ(m.host_us, host0 + 1000 + device - 30'000);
}

// The first telegrams of a connection waited (five, read at once 0.8 s after
// the last of them was sent): the estimate is young, so the timely ones that
// follow correct it at once rather than being taken as outliers for a second.
TEST(DeviceClock, ABacklogAtTheStartIsCorrectedByTheTimelyTelegramsAfterIt) {
  DeviceClock clock;
  const std::int64_t host0 = 1'700'000'000'000'000;
  std::int64_t device = 1'000'000;
  const std::int64_t read_at = host0 + device + 4 * 40'000 + 800'000;
  for (int i = 0; i < 5; ++i, device += 40'000)
    clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device), read_at);
  DeviceClock::Mapped m{};
  for (int i = 0; i < 5; ++i, device += 40'000)
    m = clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device),
                  host0 + device + 1000);
  EXPECT_EQ(m.host_us, m.device_us + host0 + 1000);
  EXPECT_EQ(clock.outliers(), 0u);
  EXPECT_EQ(clock.resets(), 0u);
}

// The host clock steps (forward 50 s, then back an hour): the estimate keeps
// the old offset until the new one has held for new_offset_after_us of device
// time, then takes it.
TEST(DeviceClock, AHostClockThatSteppedIsFollowedOnceTheNewOffsetHeld) {
  for (const std::int64_t step : {50'000'000ll, -3'600'000'000ll}) {
    DeviceClock clock;
    const std::int64_t host0 = 1'700'000'000'000'000;
    std::int64_t device = 1'000'000;
    ASSERT_EQ(settle(clock, host0, device), host0 + 1000);
    const std::int64_t first = device;
    DeviceClock::Mapped m{};
    for (; device - first < 1'000'000; device += 40'000) {
      m = clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device),
                    host0 + step + device + 1000);
      EXPECT_EQ(m.host_us, host0 + 1000 + device - 30'000) << "step " << step << ", device time " << device;
    }
    EXPECT_EQ(clock.resets(), 0u);
    m = clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device),
                  host0 + step + device + 1000);
    EXPECT_EQ(clock.resets(), 1u) << "step " << step;
    EXPECT_EQ(m.host_us, host0 + step + 1000 + device - 30'000);
    EXPECT_EQ(clock.outliers(), 26u);
  }
}

// A receive clock that was behind now and then (the simulated clock's tick
// handled after the telegram) gives samples that are too small. A few of
// them do not move the estimate; with the plain minimum one alone did, for
// the whole window.
TEST(DeviceClock, AFewEarlyReceiveStampsDoNotMoveTheEstimate) {
  DeviceClock clock;
  const std::int64_t host0 = 1'700'000'000'000'000;
  DeviceClock::Mapped m{};
  for (int i = 0; i < 250; ++i) {
    const std::int64_t device = 1'000'000 + i * 40'000ll;
    const bool behind = i % 25 == 3;  // 4 % of the samples, 70 ms behind
    const std::int64_t receive = host0 + device + (behind ? -70'000 : 0);
    m = clock.map(static_cast<std::uint32_t>(device - 30'000), static_cast<std::uint32_t>(device), receive);
  }
  EXPECT_EQ(m.host_us, host0 + m.device_us);
}

}  // namespace
}  // namespace pex::cola
