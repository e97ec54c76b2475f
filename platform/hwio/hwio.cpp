#include "hwio/hwio.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstring>

namespace pex::hwio {

Fd& Fd::operator=(Fd&& other) noexcept {
  if (this != &other) {
    reset();
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}
Fd::~Fd() { reset(); }
void Fd::reset() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

std::string errno_text(int error_number) { return std::strerror(error_number); }

// ---------------------------------------------------------------------- TCP --

Result<Fd> tcp_connect(const std::string& host, std::uint16_t port, int timeout_ms) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (::inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1) {
    return Result<Fd>::failure("not a numeric IPv4 address: '" + host + "'");
  }
  Fd fd(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!fd.valid()) return Result<Fd>::failure("socket: " + errno_text(errno));
  const int one = 1;
  ::setsockopt(fd.get(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  if (::connect(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    if (errno != EINPROGRESS) {
      return Result<Fd>::failure("connect " + host + ":" + std::to_string(port) + ": " + errno_text(errno));
    }
    pollfd p{fd.get(), POLLOUT, 0};
    const int ready = ::poll(&p, 1, timeout_ms);
    if (ready == 0) {
      return Result<Fd>::failure("connect " + host + ":" + std::to_string(port) + ": timed out after " +
                                 std::to_string(timeout_ms) + " ms");
    }
    int so_error = 0;
    socklen_t len = sizeof so_error;
    ::getsockopt(fd.get(), SOL_SOCKET, SO_ERROR, &so_error, &len);
    if (ready < 0 || so_error != 0) {
      return Result<Fd>::failure("connect " + host + ":" + std::to_string(port) + ": " +
                                 errno_text(ready < 0 ? errno : so_error));
    }
  }
  return fd;
}

Result<TcpListener> TcpListener::open_loopback(std::uint16_t port, int backlog) {
  TcpListener listener;
  listener.fd_ = Fd(::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!listener.fd_.valid()) return Result<TcpListener>::failure("socket: " + errno_text(errno));
  const int one = 1;
  ::setsockopt(listener.fd_.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);  // loopback only, by design
  if (::bind(listener.fd_.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    return Result<TcpListener>::failure("bind 127.0.0.1:" + std::to_string(port) + ": " + errno_text(errno));
  }
  if (::listen(listener.fd_.get(), backlog) != 0) {
    return Result<TcpListener>::failure("listen: " + errno_text(errno));
  }
  socklen_t len = sizeof addr;
  ::getsockname(listener.fd_.get(), reinterpret_cast<sockaddr*>(&addr), &len);
  listener.port_ = ntohs(addr.sin_port);
  return listener;
}

std::optional<Fd> TcpListener::accept() {
  const int fd = ::accept4(fd_.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return std::nullopt;
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return Fd(fd);
}

ReadResult read_some(int fd, char* buffer, std::size_t size) {
  ReadResult r;
  const ssize_t n = ::recv(fd, buffer, size, 0);
  if (n > 0) {
    r.bytes = static_cast<std::size_t>(n);
  } else if (n == 0) {
    r.closed = true;
  } else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
    r.closed = true;
    r.error = errno_text(errno);
  }
  return r;
}

bool write_all(int fd, std::string_view data, int timeout_ms, std::string* error) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n > 0) {
      data.remove_prefix(static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd, POLLOUT, 0};
      if (::poll(&p, 1, timeout_ms) <= 0) {
        if (error) *error = "write timed out";
        return false;
      }
      continue;
    }
    if (error) *error = n < 0 ? errno_text(errno) : "connection closed";
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------- CAN --

namespace {

constexpr std::size_t kFrameBytes = sizeof(struct can_frame);

struct UnixAddress {
  sockaddr_un addr{};
  socklen_t length = 0;
};

// "/path" is a socket file; "@name" is Linux's abstract namespace, which
// belongs to the network namespace (tests in private namespaces cannot
// collide) and leaves no stale file behind.
Result<UnixAddress> unix_address(const std::string& path) {
  UnixAddress a;
  a.addr.sun_family = AF_UNIX;
  if (path.size() < 2 || path.size() >= sizeof a.addr.sun_path) {
    return Result<UnixAddress>::failure("local CAN bus path too short or longer than " +
                                        std::to_string(sizeof a.addr.sun_path - 1) + " bytes: '" + path + "'");
  }
  std::memcpy(a.addr.sun_path, path.c_str(), path.size());
  if (path[0] == '@') a.addr.sun_path[0] = '\0';
  a.length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size() + (path[0] == '@' ? 0 : 1));
  return a;
}

class SocketCanTransport final : public FrameTransport {
 public:
  SocketCanTransport(Fd fd, std::string interface) : fd_(std::move(fd)), interface_(std::move(interface)) {}
  int fd() const override { return fd_.get(); }
  bool send(const struct can_frame& frame, std::string* error) override {
    const ssize_t n = ::write(fd_.get(), &frame, kFrameBytes);
    if (n == static_cast<ssize_t>(kFrameBytes)) return true;
    if (error) *error = "write to " + interface_ + ": " + (n < 0 ? errno_text(errno) : "short write");
    return false;
  }
  std::optional<struct can_frame> receive() override {
    struct can_frame frame {};
    for (;;) {
      const ssize_t n = ::read(fd_.get(), &frame, kFrameBytes);
      if (n < 0) return std::nullopt;
      if (n == static_cast<ssize_t>(kFrameBytes)) return frame;
      ++malformed_;  // CAN FD frame or short read: not ours
    }
  }
  std::string describe() const override { return "socketcan:" + interface_; }

 private:
  Fd fd_;
  std::string interface_;
};

// One end of the local bus. `server` ends remember every peer that sent to
// them and send to all; client ends send to the server path.
class LocalBusTransport final : public FrameTransport {
 public:
  LocalBusTransport(Fd fd, std::string description, std::optional<UnixAddress> server)
      : fd_(std::move(fd)), description_(std::move(description)), server_(server) {}
  int fd() const override { return fd_.get(); }

  bool send(const struct can_frame& frame, std::string* error) override {
    if (connected_pair_) return send_to(frame, nullptr, 0, error);
    if (server_) return send_to(frame, &server_->addr, server_->length, error);
    bool ok = true;
    for (std::size_t i = 0; i < peers_.size();) {
      std::string e;
      if (send_to(frame, &peers_[i].first, peers_[i].second, &e)) {
        ++i;
        continue;
      }
      if (errno == ECONNREFUSED || errno == ENOENT) {
        peers_.erase(peers_.begin() + static_cast<std::ptrdiff_t>(i));  // peer went away
        continue;
      }
      ok = false;
      if (error) *error = e;
      ++i;
    }
    return ok;
  }

  std::optional<struct can_frame> receive() override {
    for (;;) {
      struct can_frame frame {};
      char buffer[64];
      sockaddr_un from{};
      socklen_t from_len = sizeof from;
      const ssize_t n = ::recvfrom(fd_.get(), buffer, sizeof buffer, MSG_TRUNC,
                                   reinterpret_cast<sockaddr*>(&from), &from_len);
      if (n < 0) return std::nullopt;
      if (n != static_cast<ssize_t>(kFrameBytes)) {
        ++malformed_;
        continue;
      }
      std::memcpy(&frame, buffer, kFrameBytes);
      if (frame.can_dlc > CAN_MAX_DLEN) {
        ++malformed_;
        continue;
      }
      if (!server_ && !connected_pair_ && from_len > sizeof(sa_family_t)) {
        remember(from, from_len);
        relay(frame, from, from_len);
      }
      return frame;
    }
  }
  std::string describe() const override { return description_; }
  void set_connected_pair() { connected_pair_ = true; }

 private:
  bool send_to(const struct can_frame& frame, const sockaddr_un* to, socklen_t to_len, std::string* error) {
    const ssize_t n = to ? ::sendto(fd_.get(), &frame, kFrameBytes, MSG_DONTWAIT,
                                    reinterpret_cast<const sockaddr*>(to), to_len)
                         : ::send(fd_.get(), &frame, kFrameBytes, MSG_DONTWAIT);
    if (n == static_cast<ssize_t>(kFrameBytes)) return true;
    if (error) *error = description_ + ": " + (n < 0 ? errno_text(errno) : "short write");
    return false;
  }
  // A bus: what one client sends, every other client sees too.
  void relay(const struct can_frame& frame, const sockaddr_un& from, socklen_t len) {
    for (const auto& p : peers_) {
      if (p.second == len && std::memcmp(&p.first, &from, len) == 0) continue;
      send_to(frame, &p.first, p.second, nullptr);  // a gone peer is dropped on our next send
    }
  }
  void remember(const sockaddr_un& from, socklen_t len) {
    for (const auto& p : peers_) {
      if (p.second == len && std::memcmp(&p.first, &from, len) == 0) return;
    }
    if (peers_.size() < 16) peers_.emplace_back(from, len);
  }

  Fd fd_;
  std::string description_;
  std::optional<UnixAddress> server_;  // set on client ends
  std::vector<std::pair<sockaddr_un, socklen_t>> peers_;
  bool connected_pair_ = false;
};

}  // namespace

Result<std::unique_ptr<FrameTransport>> open_socketcan(const SocketCanOptions& options) {
  using R = Result<std::unique_ptr<FrameTransport>>;
  const std::string& ifname = options.interface;
  const std::string help = "load the kernel modules with `modprobe can can_raw` (and your adapter's driver) "
                           "and bring the interface up with `ip link set " + ifname +
                           " up type can bitrate 500000`";
  Fd fd(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!fd.valid()) {
    return R::failure("SocketCAN is not available for interface '" + ifname + "' (socket(PF_CAN): " +
                      errno_text(errno) + "): " + help);
  }
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) return R::failure("bad CAN interface name '" + ifname + "'");
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, ifname.c_str(), ifname.size() + 1);
  if (::ioctl(fd.get(), SIOCGIFINDEX, &ifr) != 0) {
    return R::failure("no CAN interface '" + ifname + "' (" + errno_text(errno) + "): " + help);
  }
  if (!options.filters.empty()) {
    std::vector<can_filter> filters;
    for (auto [id, mask] : options.filters) filters.push_back(can_filter{id, mask});
    if (::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                     static_cast<socklen_t>(filters.size() * sizeof(can_filter))) != 0) {
      return R::failure("CAN_RAW_FILTER on " + ifname + ": " + errno_text(errno));
    }
  }
  if (options.error_frames) {
    const can_err_mask_t mask = CAN_ERR_MASK;
    if (::setsockopt(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof mask) != 0) {
      return R::failure("CAN_RAW_ERR_FILTER on " + ifname + ": " + errno_text(errno));
    }
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    return R::failure("bind to CAN interface '" + ifname + "': " + errno_text(errno) + ": " + help);
  }
  return std::unique_ptr<FrameTransport>(new SocketCanTransport(std::move(fd), ifname));
}

Result<std::unique_ptr<FrameTransport>> open_local_bus(const std::string& path) {
  using R = Result<std::unique_ptr<FrameTransport>>;
  auto addr = unix_address(path);
  if (!addr) return R::failure(addr.error());
  Fd fd(::socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!fd.valid()) return R::failure("socket(AF_UNIX): " + errno_text(errno));
  if (path[0] != '@') ::unlink(path.c_str());  // a stale socket file from a previous run
  if (::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr->addr), addr->length) != 0) {
    return R::failure("bind local CAN bus '" + path + "': " + errno_text(errno));
  }
  return std::unique_ptr<FrameTransport>(new LocalBusTransport(std::move(fd), "local:" + path, std::nullopt));
}

Result<std::unique_ptr<FrameTransport>> connect_local_bus(const std::string& path) {
  using R = Result<std::unique_ptr<FrameTransport>>;
  auto addr = unix_address(path);
  if (!addr) return R::failure(addr.error());
  Fd fd(::socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!fd.valid()) return R::failure("socket(AF_UNIX): " + errno_text(errno));
  // Autobind: binding only the family gives the socket a unique abstract
  // address, so the bus side can answer us.
  sockaddr_un self{};
  self.sun_family = AF_UNIX;
  if (::bind(fd.get(), reinterpret_cast<sockaddr*>(&self), sizeof(sa_family_t)) != 0) {
    return R::failure("autobind local CAN client: " + errno_text(errno));
  }
  return std::unique_ptr<FrameTransport>(new LocalBusTransport(std::move(fd), "local:" + path, *addr));
}

std::pair<std::unique_ptr<FrameTransport>, std::unique_ptr<FrameTransport>> local_pair() {
  int fds[2] = {-1, -1};
  if (::socketpair(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds) != 0) return {};
  auto a = std::make_unique<LocalBusTransport>(Fd(fds[0]), "local:pair-a", std::nullopt);
  auto b = std::make_unique<LocalBusTransport>(Fd(fds[1]), "local:pair-b", std::nullopt);
  a->set_connected_pair();
  b->set_connected_pair();
  return {std::move(a), std::move(b)};
}

}  // namespace pex::hwio
