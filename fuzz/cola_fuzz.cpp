// CoLa-A from the laser: bytes as a broken or hostile LMS1xx could send them,
// through the parser (cola::StreamParser) and through the lidar reader's core
// (ReaderCore, past its login and configuration), in chunks of any size.
//
// Input: byte 0 picks the chunk size (1..128) and whether the reader
// configures the scan; the rest is the byte stream.
// Invariants: nothing crashes; every scan parsed is within the parser's limits
// and encodes to a telegram that parses back to the same encoding; every
// reply has a type "s.."; every LIDAR_SCAN the reader publishes is consistent
// (counts, finite angles, ranges NaN or in [0, +inf)), and counters add up.
#include <cmath>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "cola/cola.hpp"
#include "fuzz_check.hpp"
#include "fuzz_input.hpp"
#include "reader_core.hpp"

namespace {

using namespace pex;

void check_scan(const cola::ScanData& scan) {
  PEX_FUZZ_CHECK(scan.channels16.size() + scan.channels8.size() <= cola::kMaxChannels, "channels");
  PEX_FUZZ_CHECK(scan.encoders.size() <= cola::kMaxEncoders, "encoders");
  for (const auto* list : {&scan.channels16, &scan.channels8})
    for (const auto& c : *list) {
      PEX_FUZZ_CHECK(c.data.size() <= cola::kMaxChannelValues, std::to_string(c.data.size()));
      PEX_FUZZ_CHECK(cola::distances_m(c).size() == c.data.size(), c.content);
    }
  // The encoder is the parser's inverse: what it writes parses back and
  // encodes to the same bytes.
  const std::string once = cola::encode_scan_data(scan);
  cola::StreamParser again;
  const auto events = again.push(once);
  PEX_FUZZ_CHECK(events.size() == 1 && std::holds_alternative<cola::ScanEvent>(events[0]),
                 "a parsed scan, encoded again, does not parse: " + once.substr(0, 200));
  const std::string twice = cola::encode_scan_data(std::get<cola::ScanEvent>(events[0]).scan);
  PEX_FUZZ_CHECK(once == twice, "encoding not stable: " + once.substr(0, 200) + " / " + twice.substr(0, 200));
}

void parse_stream(std::string_view stream, std::size_t chunk) {
  cola::StreamParser parser;
  std::uint64_t events_seen = 0;
  for (std::size_t at = 0; at < stream.size(); at += chunk) {
    for (const auto& event : parser.push(stream.substr(at, chunk))) {
      ++events_seen;
      if (const auto* s = std::get_if<cola::ScanEvent>(&event)) check_scan(s->scan);
      if (const auto* r = std::get_if<cola::ReplyEvent>(&event))
        PEX_FUZZ_CHECK(r->telegram.type.size() == 3 && r->telegram.type[0] == 's', r->telegram.type);
    }
  }
  const auto& c = parser.counters();
  PEX_FUZZ_CHECK(c.scans + c.replies + c.malformed == events_seen, "counters do not add up");
  PEX_FUZZ_CHECK(parser.framer_counters().telegrams == events_seen, "framer counters");
}

void check_published(const pex::laser_scan_t& m) {
  PEX_FUZZ_CHECK(m.nranges == static_cast<std::int32_t>(m.ranges.size()) && m.nranges > 0, "nranges");
  PEX_FUZZ_CHECK(m.nintensities == static_cast<std::int32_t>(m.intensities.size()), "nintensities");
  PEX_FUZZ_CHECK(m.nintensities == 0 || m.nintensities == m.nranges, "intensities for other beams");
  PEX_FUZZ_CHECK(std::isfinite(m.angle_min) && std::isfinite(m.angle_increment) && m.angle_increment > 0,
                 "angles " + std::to_string(m.angle_min) + " " + std::to_string(m.angle_increment));
  PEX_FUZZ_CHECK(std::isfinite(m.scan_time) && m.scan_time > 0, "scan_time " + std::to_string(m.scan_time));
  for (float r : m.ranges)
    PEX_FUZZ_CHECK(std::isnan(r) || r >= 0, "range " + std::to_string(r));
}

void read_stream(std::string_view stream, std::size_t chunk, bool configure_scan) {
  lidar_reader::ReaderOptions options;
  options.configure_scan = configure_scan;
  std::int64_t published = 0;
  bool connected = false;
  std::vector<std::string> requests;
  lidar_reader::ReaderOutputs out;
  out.connect = [&](std::string*) { return connected = true; };
  out.close = [&] { connected = false; };
  out.send = [&](std::string_view bytes, std::string*) {
    requests.emplace_back(bytes);
    return true;
  };
  out.publish_scan = [&](const pex::laser_scan_t& m) {
    check_published(m);
    ++published;
  };
  out.report = [](const pex::runtime::DaemonHealth&) {};
  out.note = [](const std::string&) {};
  out.error = [](std::string_view, const std::string&) {};
  out.reject = [](std::string_view, const std::string&) {};
  lidar_reader::ReaderCore core(options, out);

  std::int64_t now_us = 1'000'000;
  const std::int64_t utime0 = 1'700'000'000'000'000;
  core.poll(now_us);
  PEX_FUZZ_CHECK(connected && core.phase() == lidar_reader::ReaderCore::Phase::kConfiguring, "no connection");
  // The sensor's answers to the configuration, so the stream that follows
  // meets a reader that is streaming.
  std::string handshake = cola::encode_reply("sAN", "SetAccessMode", {"1"});
  if (configure_scan) handshake += cola::encode_reply("sAN", "mLMPsetscancfg", {"0"});
  handshake += cola::encode_reply("sWA", "LMDscandatacfg", {});
  handshake += cola::encode_reply("sWA", "LMPoutputRange", {});
  handshake += cola::encode_reply("sAN", "LMCstartmeas", {"0"});
  handshake += cola::encode_reply("sAN", "Run", {"1"});
  handshake += cola::encode_reply("sEA", "LMDscandata", {"1"});
  core.on_bytes(handshake, now_us, utime0 + now_us);
  PEX_FUZZ_CHECK(core.phase() == lidar_reader::ReaderCore::Phase::kStreaming, "handshake did not complete");

  for (std::size_t at = 0; at < stream.size(); at += chunk) {
    now_us += 40'000;
    core.on_bytes(stream.substr(at, chunk), now_us, utime0 + now_us);
    core.poll(now_us);
  }
  PEX_FUZZ_CHECK(core.counters().scans_published == published, "scans_published");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pex::fuzz::Input in(data, size);
  const std::uint8_t head = in.byte();
  const std::size_t chunk = 1 + (head >> 1);
  const std::string_view stream = in.rest();
  parse_stream(stream, chunk);
  read_stream(stream, chunk, head & 1);
  return 0;
}
