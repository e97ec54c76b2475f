// One LCM message on any registered channel, as a daemon receives it:
// Node::dispatch -> the type's bounded decoder -> the handler.
//
// Input: byte 0 picks the channel (registry order, modulo its size); the
// rest is the datagram's payload.
// Invariants: nothing crashes; the message is either rejected (counted, the
// node goes on) or decoded into a message that encodes in no more bytes than
// it came in, and whose encoding is stable.
#include <cstdint>

#include <spdlog/spdlog.h>

#include "fuzz_input.hpp"
#include "lcm_channels.hpp"

namespace {

pex::runtime::NodeOptions offline_node() {
  pex::runtime::NodeOptions options;
  options.name = "fuzz";
  options.offline = true;
  return options;
}

struct Bus {
  pex::runtime::Node node{offline_node()};
  std::int64_t decoded = 0;
  int size = 0;
  Bus() { pex::fuzz::subscribe_every_channel(node, decoded, size); }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  spdlog::set_level(spdlog::level::err);  // rejections are warnings; a handler's failure shows
  static Bus bus;
  pex::fuzz::Input in(data, size);
  const auto& channel = pex::runtime::channels::kRegistry[in.byte() % pex::runtime::channels::kRegistry.size()];
  const std::string_view payload = in.rest();
  bus.size = static_cast<int>(payload.size());
  const std::int64_t decoded_before = bus.decoded;
  const std::int64_t rejected_before = bus.node.msgs_rejected();
  const std::int64_t errors_before = bus.node.errors();
  bus.node.dispatch(channel.name, payload.data(), static_cast<int>(payload.size()), 1'700'000'000'000'000);
  const int outcomes = static_cast<int>(bus.decoded - decoded_before) +
                       static_cast<int>(bus.node.msgs_rejected() - rejected_before);
  PEX_FUZZ_CHECK(outcomes == 1, std::string(channel.name) + ": decoded and rejected " + std::to_string(outcomes) + " times");
  // A decoder that throws (std::bad_alloc, std::length_error) is an error of
  // the daemon, not rejected input: the bounded decoders never do.
  // (errors() counts the rejections too.)
  PEX_FUZZ_CHECK(bus.node.errors() - errors_before == bus.node.msgs_rejected() - rejected_before,
                 std::string(channel.name) + ": decoding failed with an exception");
  return 0;
}
