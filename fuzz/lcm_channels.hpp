#pragma once
// Every registered channel (runtime/channels.hpp) subscribed on a Node with
// its message type, as the daemons subscribe: the project's bounded decoders
// (cmake/PexLcmBoundedDecode.cmake) behind Node::subscribe. Shared by the
// message and the log fuzz targets.
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/mission_cmd_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/sim_fault_t.hpp>
#include <pex/slam_update_t.hpp>
#include <pex/velocity_cmd_t.hpp>

#include "fuzz_check.hpp"
#include "runtime/channels.hpp"
#include "runtime/node.hpp"

namespace pex::fuzz {

// What a decoded message must satisfy: it takes no more bytes to encode than
// it came in (so nothing was allocated beyond what the bytes could encode),
// and its encoding decodes to a message with the same encoding.
template <class Msg>
void check_decoded(const Msg& msg, int size) {
  const int encoded_size = msg.getEncodedSize();
  PEX_FUZZ_CHECK(encoded_size >= 0 && encoded_size <= size,
                 std::string(Msg::getTypeName()) + " of " + std::to_string(size) + " bytes encodes to " +
                     std::to_string(encoded_size));
  std::vector<std::uint8_t> once(static_cast<std::size_t>(encoded_size));
  const int written = msg.encode(once.data(), 0, encoded_size);
  PEX_FUZZ_CHECK(written > 0 && written <= encoded_size, "encode wrote " + std::to_string(written));
  Msg again{};
  PEX_FUZZ_CHECK(again.decode(once.data(), 0, written) == written,
                 std::string(Msg::getTypeName()) + ": its own encoding does not decode");
  std::vector<std::uint8_t> twice(static_cast<std::size_t>(again.getEncodedSize()));
  const int written_again = again.encode(twice.data(), 0, static_cast<int>(twice.size()));
  PEX_FUZZ_CHECK(written_again == written && std::equal(once.begin(), once.begin() + written, twice.begin()),
                 std::string(Msg::getTypeName()) + ": encoding not stable");
}

// Subscribes every channel of the registry; `decoded` counts the messages
// that reached their handler, each checked against `max_size` bytes.
inline void subscribe_every_channel(runtime::Node& node, std::int64_t& decoded, const int& max_size) {
  namespace ch = runtime::channels;
  std::vector<std::string_view> done;
  auto add = [&]<class Msg>(std::string_view channel, Msg*) {
    node.subscribe<Msg>(channel, [&decoded, &max_size](const Msg& msg) {
      check_decoded(msg, max_size);
      ++decoded;
    });
    done.push_back(channel);
  };
  add(ch::kLidarScan, static_cast<pex::laser_scan_t*>(nullptr));
  add(ch::kOdometry, static_cast<pex::odometry_t*>(nullptr));
  add(ch::kBaseCmd, static_cast<pex::velocity_cmd_t*>(nullptr));
  add(ch::kSlamUpdate, static_cast<pex::slam_update_t*>(nullptr));
  add(ch::kSlamPose, static_cast<pex::pose_t*>(nullptr));
  add(ch::kMap, static_cast<pex::polygon_map_t*>(nullptr));
  add(ch::kMapFree, static_cast<pex::polygon_map_t*>(nullptr));
  add(ch::kExploreState, static_cast<pex::explore_state_t*>(nullptr));
  add(ch::kDaemonStatus, static_cast<pex::daemon_status_t*>(nullptr));
  add(ch::kSimTruth, static_cast<pex::pose_t*>(nullptr));
  add(ch::kSimClock, static_cast<pex::sim_clock_t*>(nullptr));
  add(ch::kMissionCmd, static_cast<pex::mission_cmd_t*>(nullptr));
  add(ch::kSimFault, static_cast<pex::sim_fault_t*>(nullptr));
  add(ch::kKeepOut, static_cast<pex::polygon_map_t*>(nullptr));
  // A channel added to the registry must be added here too.
  for (const auto& c : ch::kRegistry)
    PEX_FUZZ_CHECK(std::find(done.begin(), done.end(), c.name) != done.end(),
                   std::string(c.name) + " is registered but not fuzzed");
}

}  // namespace pex::fuzz
