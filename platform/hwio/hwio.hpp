#pragma once
// Device I/O for the hardware daemons and the simulator: TCP on loopback (or
// a configured sensor address for the client), and the CAN frame-transport
// seam. Everything here is non-blocking and hands out file descriptors, so a
// daemon can watch them in its event loop; nothing here logs or sleeps.
#include <linux/can.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace pex::hwio {

// An owned file descriptor (closed on destruction).
class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  Fd(Fd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Fd& operator=(Fd&& other) noexcept;
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd();
  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  void reset();

 private:
  int fd_ = -1;
};

// A value or the text of what went wrong (std::expected is C++23).
template <class T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit on purpose
  static Result failure(std::string message) { return Result(Error{std::move(message)}); }
  explicit operator bool() const { return std::holds_alternative<T>(value_); }
  T& operator*() { return std::get<T>(value_); }
  T* operator->() { return &std::get<T>(value_); }
  const std::string& error() const { return std::get<Error>(value_).message; }

 private:
  struct Error {
    std::string message;
  };
  explicit Result(Error e) : value_(std::move(e)) {}
  std::variant<T, Error> value_;
};

std::string errno_text(int error_number);

// ---------------------------------------------------------------------- TCP --

// Connects to host:port (numeric IPv4 address) within timeout_ms; the socket
// is non-blocking with TCP_NODELAY.
Result<Fd> tcp_connect(const std::string& host, std::uint16_t port, int timeout_ms);

// A listening socket on 127.0.0.1 only (port 0 picks a free port).
class TcpListener {
 public:
  static Result<TcpListener> open_loopback(std::uint16_t port, int backlog = 8);
  int fd() const { return fd_.get(); }
  std::uint16_t port() const { return port_; }
  // A pending connection (non-blocking), or nullopt when there is none.
  std::optional<Fd> accept();

 private:
  Fd fd_;
  std::uint16_t port_ = 0;
};

// Outcome of a non-blocking read.
struct ReadResult {
  std::size_t bytes = 0;
  bool closed = false;      // peer closed (EOF) or the connection failed
  std::string error;        // set when closed because of an error
};
ReadResult read_some(int fd, char* buffer, std::size_t size);

// Writes all of `data`, waiting up to timeout_ms for buffer space; false and
// an error text when the peer is gone or too slow.
bool write_all(int fd, std::string_view data, int timeout_ms, std::string* error);

// ---------------------------------------------------------------------- CAN --

// Moves `struct can_frame` bytes. Both implementations deliver error frames
// (CAN_ERR_FLAG in can_id) as frames, so the user sees bus errors in-band.
class FrameTransport {
 public:
  virtual ~FrameTransport() = default;
  // The descriptor to watch for readability.
  virtual int fd() const = 0;
  // Sends one frame; false with a reason when it could not be sent.
  virtual bool send(const struct can_frame& frame, std::string* error) = 0;
  // One received frame, or nullopt when none is pending. Datagrams of the
  // wrong size are dropped and counted in malformed().
  virtual std::optional<struct can_frame> receive() = 0;
  virtual std::string describe() const = 0;
  std::uint64_t malformed() const { return malformed_; }

 protected:
  std::uint64_t malformed_ = 0;
};

struct SocketCanOptions {
  std::string interface = "can0";
  // Receive filters (id, mask) as CAN_RAW_FILTER; empty = everything.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> filters;
  bool error_frames = true;  // subscribe to all error classes (CAN_RAW_ERR_FILTER)
};

// SocketCAN (PF_CAN, SOCK_RAW, CAN_RAW) on a kernel interface. Fails with a
// message naming the interface and what to load when the kernel has no CAN.
Result<std::unique_ptr<FrameTransport>> open_socketcan(const SocketCanOptions& options);

// A local bus over Unix datagram sockets carrying the same 16-byte frames.
// `path` is a socket file ("/tmp/pex-can.sock") or, starting with "@", a name
// in the abstract namespace of the network namespace ("@pex-can").
// The simulator binds `path` (removing a stale socket file); a client binds an
// abstract autobind address and sends to `path`. The bound side sends every
// frame to each client it has heard from and relays each client's frames to
// the other clients, so all ends see all traffic, like a bus.
Result<std::unique_ptr<FrameTransport>> open_local_bus(const std::string& path);
Result<std::unique_ptr<FrameTransport>> connect_local_bus(const std::string& path);
// Two connected ends in one process (tests).
std::pair<std::unique_ptr<FrameTransport>, std::unique_ptr<FrameTransport>> local_pair();

}  // namespace pex::hwio
