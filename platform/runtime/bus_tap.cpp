#include "runtime/bus_tap.hpp"

#include <arpa/inet.h>
#include <linux/filter.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace pex::runtime {

namespace {
constexpr std::uint32_t kShortMagic = 0x4c433032;  // "LC02": a whole message in one datagram
constexpr std::string_view kDefaultUrl = "udpm://239.255.76.67:7667";
}  // namespace

std::optional<UdpmAddress> parse_udpm_url(std::string_view url) {
  if (url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    url = env && *env ? std::string_view(env) : kDefaultUrl;
  }
  constexpr std::string_view kScheme = "udpm://";
  if (url.substr(0, kScheme.size()) != kScheme) return std::nullopt;
  std::string_view rest = url.substr(kScheme.size());
  rest = rest.substr(0, rest.find('?'));
  UdpmAddress a;
  a.group = "239.255.76.67";
  a.port = 7667;
  if (rest.empty()) return a;
  const auto colon = rest.find(':');
  if (colon != std::string_view::npos) {
    const std::string port(rest.substr(colon + 1));
    char* end = nullptr;
    const long p = std::strtol(port.c_str(), &end, 10);
    if (port.empty() || *end != '\0' || p <= 0 || p > 65535) return std::nullopt;
    a.port = static_cast<std::uint16_t>(p);
    rest = rest.substr(0, colon);
  }
  if (!rest.empty()) a.group = std::string(rest);
  in_addr probe{};
  if (inet_pton(AF_INET, a.group.c_str(), &probe) != 1) return std::nullopt;
  return a;
}

std::optional<LcmPacket> parse_lcm_packet(const std::uint8_t* bytes, std::size_t size) {
  if (size < 9) return std::nullopt;
  const std::uint32_t magic = (std::uint32_t{bytes[0]} << 24) | (std::uint32_t{bytes[1]} << 16) |
                              (std::uint32_t{bytes[2]} << 8) | std::uint32_t{bytes[3]};
  if (magic != kShortMagic) return std::nullopt;
  const auto* name = reinterpret_cast<const char*>(bytes + 8);
  const void* nul = std::memchr(name, '\0', size - 8);
  if (!nul) return std::nullopt;
  LcmPacket p;
  p.channel = std::string_view(name, static_cast<std::size_t>(static_cast<const char*>(nul) - name));
  p.data = bytes + 8 + p.channel.size() + 1;
  p.size = size - 8 - p.channel.size() - 1;
  return p;
}

BusTap::BusTap(const UdpmAddress& address, std::string channel) : channel_(std::move(channel)) {
  // BPF jumps are 8 bits: two instructions a byte must stay below 256.
  if (channel_.empty() || channel_.size() > 100)
    throw std::runtime_error("bus tap: channel name must have 1 to 100 characters");
  auto fail = [&](const std::string& what) {
    const std::string message = what + ": " + std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    throw std::runtime_error("bus tap on " + address.group + ":" + std::to_string(address.port) + ": " + message);
  };
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) fail("socket");
  const int one = 1;
  // LCM binds the same port with SO_REUSEADDR: every socket joined to the
  // group gets its own copy of each datagram.
  if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0) fail("SO_REUSEADDR");
  sockaddr_in bind_address{};
  bind_address.sin_family = AF_INET;
  bind_address.sin_port = htons(address.port);
  bind_address.sin_addr.s_addr = htonl(INADDR_ANY);  // as LCM does; the group filters below
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&bind_address), sizeof bind_address) < 0) fail("bind");
  ip_mreq membership{};
  inet_pton(AF_INET, address.group.c_str(), &membership.imr_multiaddr);
  membership.imr_interface.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) < 0) fail("join group");
  // Only our channel's datagrams are queued: the bus carries scans and maps
  // at megabytes a second, and a full queue would drop exactly the ticks the
  // tap is for. A classic BPF program compares the LCM header ("LC02",
  // sequence number) and the channel name with its NUL; the filter sees the
  // datagram from its UDP header on (8 bytes).
  constexpr std::uint32_t kUdpHeader = 8;
  std::vector<sock_filter> program;
  std::string expected = "LC02xxxx" + channel_;
  expected.push_back('\0');
  std::uint32_t compares_left = static_cast<std::uint32_t>(expected.size() - 4);
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (i >= 4 && i < 8) continue;  // the sequence number
    --compares_left;
    program.push_back(BPF_STMT(BPF_LD | BPF_B | BPF_ABS, kUdpHeader + static_cast<std::uint32_t>(i)));
    // On a mismatch jump to the reject: past the remaining compares and the accept.
    program.push_back(BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, static_cast<std::uint8_t>(expected[i]), 0,
                               static_cast<std::uint8_t>(2 * compares_left + 1)));
  }
  program.push_back(BPF_STMT(BPF_RET | BPF_K, 0xFFFFFFFFu));  // accept whole
  program.push_back(BPF_STMT(BPF_RET | BPF_K, 0));            // reject
  sock_fprog fprog{static_cast<unsigned short>(program.size()), program.data()};
  if (::setsockopt(fd_, SOL_SOCKET, SO_ATTACH_FILTER, &fprog, sizeof fprog) < 0) fail("attach filter");
}

BusTap::~BusTap() {
  if (fd_ >= 0) ::close(fd_);
}

int BusTap::drain(const std::function<void(const void*, int)>& fn) {
  // Big enough for any datagram; messages that are not ours are dropped whole.
  static thread_local std::vector<std::uint8_t> buffer(65536);
  int delivered = 0;
  for (;;) {
    const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR) continue;
      break;  // EAGAIN: empty
    }
    const auto packet = parse_lcm_packet(buffer.data(), static_cast<std::size_t>(n));
    if (!packet || packet->channel != channel_) continue;
    fn(packet->data, static_cast<int>(packet->size));
    ++delivered;
  }
  return delivered;
}

}  // namespace pex::runtime
