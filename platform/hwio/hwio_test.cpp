#include "hwio/hwio.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>

namespace pex::hwio {
namespace {

// Waits (bounded) until fd is readable; the bound only guards against a hang.
bool wait_readable(int fd) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, 5000) == 1;
}

struct can_frame frame(std::uint32_t id, std::uint8_t dlc, std::uint8_t first) {
  struct can_frame f {};
  f.can_id = id;
  f.can_dlc = dlc;
  f.data[0] = first;
  return f;
}

std::string temp_path(const char* name) {
  return std::string("/tmp/pex-hwio-test-") + std::to_string(::getpid()) + "-" + name;
}

TEST(Tcp, LoopbackListenerConnectReadWrite) {
  auto listener = TcpListener::open_loopback(0);
  ASSERT_TRUE(listener) << listener.error();
  ASSERT_GT(listener->port(), 0);
  auto client = tcp_connect("127.0.0.1", listener->port(), 2000);
  ASSERT_TRUE(client) << client.error();
  ASSERT_TRUE(wait_readable(listener->fd()));
  auto server_side = listener->accept();
  ASSERT_TRUE(server_side.has_value());
  std::string error;
  ASSERT_TRUE(write_all(client->get(), "hello", 1000, &error)) << error;
  ASSERT_TRUE(wait_readable(server_side->get()));
  char buffer[16];
  ReadResult r = read_some(server_side->get(), buffer, sizeof buffer);
  EXPECT_EQ(std::string(buffer, r.bytes), "hello");
  EXPECT_FALSE(r.closed);
  // Nothing pending: a non-blocking read says so without closing.
  r = read_some(server_side->get(), buffer, sizeof buffer);
  EXPECT_EQ(r.bytes, 0u);
  EXPECT_FALSE(r.closed);
  client->reset();
  ASSERT_TRUE(wait_readable(server_side->get()));
  r = read_some(server_side->get(), buffer, sizeof buffer);
  EXPECT_TRUE(r.closed);
}

TEST(Tcp, ConnectErrorsAreReported) {
  auto listener = TcpListener::open_loopback(0);
  ASSERT_TRUE(listener);
  const std::uint16_t port = listener->port();
  *listener = TcpListener{};  // close it: nobody listens on that port now
  auto refused = tcp_connect("127.0.0.1", port, 1000);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find(std::to_string(port)), std::string::npos);
  auto bad = tcp_connect("localhost.invalid", 2111, 1000);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find("IPv4"), std::string::npos);
}

TEST(SocketCan, MissingSupportOrInterfaceGivesAClearError) {
  SocketCanOptions options;
  options.interface = "pexcan9";  // no such interface on any machine we know
  auto transport = open_socketcan(options);
  ASSERT_FALSE(transport);
  EXPECT_NE(transport.error().find("pexcan9"), std::string::npos) << transport.error();
  EXPECT_NE(transport.error().find("modprobe can can_raw"), std::string::npos) << transport.error();
  EXPECT_NE(transport.error().find("ip link set pexcan9 up type can bitrate"), std::string::npos);
}

TEST(LocalBus, FramesBothWaysAndToSeveralClients) {
  const std::string path = temp_path("bus");
  auto bus = open_local_bus(path);
  ASSERT_TRUE(bus) << bus.error();
  auto a = connect_local_bus(path);
  auto b = connect_local_bus(path);
  ASSERT_TRUE(a && b);
  std::string error;
  ASSERT_TRUE((*a)->send(frame(0x181, 6, 0x27), &error)) << error;
  ASSERT_TRUE((*b)->send(frame(0x182, 6, 0x28), &error)) << error;
  ASSERT_TRUE(wait_readable((*bus)->fd()));
  auto f1 = (*bus)->receive();
  ASSERT_TRUE(wait_readable((*bus)->fd()));
  auto f2 = (*bus)->receive();
  ASSERT_TRUE(f1 && f2);
  EXPECT_EQ(f1->can_id, 0x181u);
  EXPECT_EQ(f2->can_id, 0x182u);
  EXPECT_EQ(f2->data[0], 0x28);
  // The bus side now knows both clients and reaches each; b's frame was also
  // relayed to a (a bus: everyone sees everything). a's frame reached the bus
  // before b was known, so b never saw it.
  ASSERT_TRUE((*bus)->send(frame(0x080, 0, 0), &error)) << error;
  std::vector<std::uint32_t> seen_by_a, seen_by_b;
  for (auto [client, seen] : {std::pair{&*a, &seen_by_a}, std::pair{&*b, &seen_by_b}}) {
    ASSERT_TRUE(wait_readable((*client)->fd()));
    while (auto f = (*client)->receive()) seen->push_back(f->can_id);
  }
  EXPECT_EQ(seen_by_a, (std::vector<std::uint32_t>{0x182, 0x080}));
  EXPECT_EQ(seen_by_b, (std::vector<std::uint32_t>{0x080}));
  ::unlink(path.c_str());
}

TEST(LocalBus, WrongSizedDatagramsAreCountedAndDropped) {
  const std::string path = temp_path("junk");
  auto bus = open_local_bus(path);
  ASSERT_TRUE(bus);
  int raw = ::socket(AF_UNIX, SOCK_DGRAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strcpy(addr.sun_path, path.c_str());
  const char junk[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(::sendto(raw, junk, sizeof junk, 0, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 5);
  struct can_frame bad_dlc = frame(0x181, 200, 0);
  ASSERT_EQ(::sendto(raw, &bad_dlc, sizeof bad_dlc, 0, reinterpret_cast<sockaddr*>(&addr), sizeof addr),
            static_cast<ssize_t>(sizeof bad_dlc));
  struct can_frame good = frame(0x701, 1, 5);
  ASSERT_EQ(::sendto(raw, &good, sizeof good, 0, reinterpret_cast<sockaddr*>(&addr), sizeof addr),
            static_cast<ssize_t>(sizeof good));
  ASSERT_TRUE(wait_readable((*bus)->fd()));
  auto f = (*bus)->receive();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->can_id, 0x701u);
  EXPECT_EQ((*bus)->malformed(), 2u);
  ::close(raw);
  ::unlink(path.c_str());
}

TEST(LocalBus, ClientWithoutBusReportsSendError) {
  auto client = connect_local_bus(temp_path("nobody"));
  ASSERT_TRUE(client);
  std::string error;
  EXPECT_FALSE((*client)->send(frame(0x080, 0, 0), &error));
  EXPECT_FALSE(error.empty());
  auto too_long = open_local_bus(std::string(200, 'x'));
  EXPECT_FALSE(too_long);
}

TEST(LocalBus, PairCarriesErrorFramesInBand) {
  auto [a, b] = local_pair();
  ASSERT_TRUE(a && b);
  std::string error;
  ASSERT_TRUE(a->send(frame(CAN_ERR_FLAG | 0x40, 8, 0), &error));
  ASSERT_TRUE(wait_readable(b->fd()));
  auto f = b->receive();
  ASSERT_TRUE(f);
  EXPECT_TRUE(f->can_id & CAN_ERR_FLAG);
}

}  // namespace
}  // namespace pex::hwio

namespace pex::hwio {
namespace {

TEST(LocalBus, AbstractNamespaceAddress) {
  const std::string name = "@pex-hwio-test-" + std::to_string(::getpid());
  auto bus = open_local_bus(name);
  ASSERT_TRUE(bus) << bus.error();
  auto client = connect_local_bus(name);
  ASSERT_TRUE(client);
  std::string error;
  struct can_frame f {};
  f.can_id = 0x701;
  f.can_dlc = 1;
  ASSERT_TRUE((*client)->send(f, &error)) << error;
  pollfd p{(*bus)->fd(), POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 5000), 1);
  auto got = (*bus)->receive();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->can_id, 0x701u);
  // Another bus on the same name is refused while this one lives.
  EXPECT_FALSE(open_local_bus(name));
}

}  // namespace
}  // namespace pex::hwio
