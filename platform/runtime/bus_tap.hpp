#pragma once
// A second, synchronous receiver of one LCM channel on a udpm bus.
//
// Why: LCM's udpm provider reads the socket on its own thread and hands
// messages over through a pipe, so a daemon cannot know whether a SIM_CLOCK
// tick the simulator sent *before* a scan telegram (TCP) or CAN frame has been
// handed over yet. On clock = "sim" that made a reader stamp scans with a tick
// several steps old (tens of ms at x10 under load), and the scan clock's
// minimum filter kept the worst such stamp for 250 scans: scans paired with
// poses 40-100 ms too early, walls smeared into doorways while turning. This
// tap owns its own socket on the bus's group and port, read in the daemon's
// own thread: drained before any fd data is handled, it always holds every
// tick the simulator sent before that data (loopback delivers in order).
//
// Only small messages (LCM "LC02" packets) are decoded; everything else on
// the bus is read and dropped.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace pex::runtime {

struct UdpmAddress {
  std::string group;  // dotted IPv4 multicast group
  std::uint16_t port = 0;
};
// The group and port of an LCM URL ("" = LCM_DEFAULT_URL or LCM's default);
// nullopt for a provider other than udpm (memq://, file://, ...).
std::optional<UdpmAddress> parse_udpm_url(std::string_view url);

// The channel and payload of one LCM datagram, if it is a whole (not
// fragmented) message; nullopt otherwise.
struct LcmPacket {
  std::string_view channel;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};
std::optional<LcmPacket> parse_lcm_packet(const std::uint8_t* bytes, std::size_t size);

class BusTap {
 public:
  // Throws std::runtime_error when the socket cannot be opened or joined.
  BusTap(const UdpmAddress& address, std::string channel);
  ~BusTap();
  BusTap(const BusTap&) = delete;
  BusTap& operator=(const BusTap&) = delete;

  int fd() const { return fd_; }
  // Reads every datagram waiting; calls `fn` for each message on the channel,
  // oldest first. Returns how many it delivered.
  int drain(const std::function<void(const void* data, int size)>& fn);

 private:
  int fd_ = -1;
  std::string channel_;
};

}  // namespace pex::runtime
