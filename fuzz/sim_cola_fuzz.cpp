// CoLa-A requests to the simulated LMS111: bytes as a broken or hostile client
// of pex-sim's laser port could send them, through the simulator's request
// parser (cola::StreamParser, as pex-sim runs it per client) and its protocol
// side (simd::Lms111Protocol::answer), in chunks of any size.
//
// Input: byte 0 picks the chunk size (1..128); the rest is the byte stream.
// Invariants: nothing crashes; every request gets exactly one framed answer
// that parses back as an answer (sAN, sRA, sWA, sEA or sFA); the client's
// access level changes only by SetAccessMode with a listed level and its
// password (up) or by Run (back to 0); streaming changes only by sEN
// LMDscandata.
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

#include "cola/cola.hpp"
#include "fuzz_check.hpp"
#include "fuzz_input.hpp"
#include "simulator.hpp"

namespace {

using namespace pex;

bool is_answer_type(const std::string& type) {
  return type == "sAN" || type == "sRA" || type == "sWA" || type == "sEA" || type == "sFA";
}

// What the request does to the client's access level, by the listing.
bool level_change_allowed(const cola::Telegram& request, int before, int after) {
  if (after == before) return true;
  if (request.type == "sMN" && request.name == "Run") return after == 0;
  if (request.type != "sMN" || request.name != "SetAccessMode" || request.args.size() != 2) return false;
  const auto hash = cola::parse_uint(request.args[1], 0xFFFFFFFF);
  return (after == cola::kUserLevelAuthorizedClient && hash == cola::kPasswordAuthorizedClient) ||
         (after == cola::kUserLevelMaintenance && hash == cola::kPasswordMaintenance);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pex::fuzz::Input in(data, size);
  const std::size_t chunk = 1 + (in.byte() >> 1);
  const std::string_view stream = in.rest();

  static const simd::SimOptions options;  // the protocol keeps a reference
  simd::Lms111Protocol protocol(options);
  simd::ColaClient client;
  for (std::size_t at = 0; at < stream.size(); at += chunk) {
    for (const auto& event : client.parser.push(stream.substr(at, chunk))) {
      const auto* request = std::get_if<cola::ReplyEvent>(&event);
      if (!request) continue;  // scan data or a malformed telegram: not answered
      const int level_before = client.access_level;
      const bool streaming_before = client.streaming;
      const std::string answer = protocol.answer(client, request->telegram);

      cola::StreamParser reader;
      const auto parsed = reader.push(answer);
      PEX_FUZZ_CHECK(parsed.size() == 1, "the answer is not one telegram: " + answer.substr(0, 200));
      const auto* reply = std::get_if<cola::ReplyEvent>(&parsed[0]);
      PEX_FUZZ_CHECK(reply && is_answer_type(reply->telegram.type), "not an answer: " + answer.substr(0, 200));
      PEX_FUZZ_CHECK(level_change_allowed(request->telegram, level_before, client.access_level),
                     request->telegram.type + " " + request->telegram.name + " changed the access level from " +
                         std::to_string(level_before) + " to " + std::to_string(client.access_level));
      PEX_FUZZ_CHECK(client.streaming == streaming_before ||
                         (request->telegram.type == "sEN" && request->telegram.name == "LMDscandata"),
                     request->telegram.type + " " + request->telegram.name + " changed streaming");
    }
  }
  return 0;
}
