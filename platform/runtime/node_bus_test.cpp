// On clock = "sim" over a real udpm bus (private network namespace): data the
// simulator writes to an fd right after a SIM_CLOCK tick is handled at that
// tick. Through LCM alone it was not: LCM's receive thread may not have
// handed the tick over yet, and the scan stamps fell behind (bus_tap.hpp).
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>

#include <atomic>
#include <vector>
#include <thread>

#include <lcm/lcm-cpp.hpp>
#include <pex/sim_clock_t.hpp>

#include "runtime/channels.hpp"
#include "runtime/node.hpp"
#include "runtime/daemon_state.hpp"
#include "runtime/log_capture.hpp"
#include <pex/daemon_status_t.hpp>

using pex::runtime::ClockSource;
using pex::runtime::Node;
using pex::runtime::NodeOptions;

namespace {
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr std::int64_t kEpoch = 1'700'000'000'000'000;
}  // namespace

TEST(NodeSimClockOnUdpm, FdDataIsHandledAtTheTickSentBeforeIt) {
  NodeOptions options{"t", kUrl, false, "", 1.0};
  options.clock = ClockSource::kSim;
  Node node(options);
  lcm::LCM simulator(kUrl);
  ASSERT_TRUE(simulator.good());
  int pair[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair), 0);

  constexpr int kTicks = 400;
  std::atomic<int> handled{0};
  std::atomic<bool> stop{false};
  int late = 0;  // data handled with an older tick than the one sent before it
  std::int64_t worst_lag_us = 0;
  node.watch_fd(pair[0], [&] {
    std::int32_t k = 0;
    if (::read(pair[0], &k, sizeof k) != sizeof k) return;
    if (k < 0) return node.request_stop();  // the guard
    const std::int64_t expected = kEpoch + 10'000 * static_cast<std::int64_t>(k);
    if (node.now_utime() < expected) {
      ++late;
      worst_lag_us = std::max(worst_lag_us, expected - node.now_utime());
    }
    if (handled.fetch_add(1) + 1 == kTicks) node.request_stop();
  });
  // The simulator: a tick, then at once the data of that step; the next step
  // once the node has handled it.
  std::thread sim([&] {
    for (std::int32_t k = 1; k <= kTicks && !stop; ++k) {
      pex::sim_clock_t c{};
      c.sim_time_us = 10'000 * static_cast<std::int64_t>(k);
      c.utime = kEpoch + c.sim_time_us;
      c.speed_factor = 10.0;
      simulator.publish(std::string(pex::runtime::channels::kSimClock), &c);
      if (::write(pair[1], &k, sizeof k) != sizeof k) break;
      while (handled.load() < k && !stop) std::this_thread::yield();
    }
  });
  std::thread guard([&] {  // only so that a broken loop fails instead of hanging
    for (int i = 0; i < 600 && !stop && handled.load() < kTicks; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (handled.load() < kTicks) {
      const std::int32_t k = -1;
      (void)!::write(pair[1], &k, sizeof k);
    }
  });
  node.run();
  stop = true;
  sim.join();
  guard.join();
  ::close(pair[0]);
  ::close(pair[1]);
  EXPECT_EQ(handled.load(), kTicks);
  EXPECT_EQ(late, 0) << "worst: " << worst_lag_us << " us behind";
  EXPECT_EQ(node.counter("sim_clock_rejected"), 0);
}

// The tap's socket queues only its channel (a kernel filter): a flood of other
// traffic, or a channel whose name merely starts the same, never reaches it.
TEST(BusTapOnUdpm, QueuesOnlyItsChannel) {
  const auto address = pex::runtime::parse_udpm_url(kUrl);
  ASSERT_TRUE(address);
  pex::runtime::BusTap tap(*address, "SIM_CLOCK");
  lcm::LCM bus(kUrl);
  ASSERT_TRUE(bus.good());
  const std::vector<std::uint8_t> big(4000, 7);
  for (int i = 0; i < 50; ++i) {
    bus.publish("LIDAR_SCAN", big.data(), static_cast<unsigned>(big.size()));
    bus.publish("SIM_CLOCKS", big.data(), 10);
    bus.publish("SIM_CLOC", big.data(), 10);
  }
  const std::uint8_t payload[3] = {1, 2, 3};
  for (int i = 0; i < 5; ++i) bus.publish("SIM_CLOCK", payload, sizeof payload);
  // Read the socket itself: every datagram queued must be one of the five.
  int queued = 0;
  std::vector<std::uint8_t> datagram(65536);
  for (int tries = 0; tries < 100000 && queued < 5; ++tries) {
    const ssize_t n = ::recv(tap.fd(), datagram.data(), datagram.size(), MSG_DONTWAIT);
    if (n < 0) continue;  // loopback delivery is done when publish returns; this only guards a slow kernel
    const auto packet = pex::runtime::parse_lcm_packet(datagram.data(), static_cast<std::size_t>(n));
    ASSERT_TRUE(packet);
    EXPECT_EQ(packet->channel, "SIM_CLOCK");
    ++queued;
  }
  EXPECT_EQ(queued, 5);
  std::uint8_t byte;
  EXPECT_LT(::recv(tap.fd(), &byte, 1, MSG_DONTWAIT), 0);
}

// Health as words, where a person reads it: the journal ("state DEGRADED: why") and
// systemd's status line (STATUS=DEGRADED (why), ...: `systemctl status`), taken here
// from a NOTIFY_SOCKET of the test's own, as systemd would receive it.
TEST(NodeHealthWords, JournalAndSystemdStatusSayTheStateInWords) {
  EXPECT_STREQ(pex::runtime::daemon_state_name(pex::daemon_status_t::STATE_STARTING), "STARTING");
  EXPECT_STREQ(pex::runtime::daemon_state_name(pex::daemon_status_t::STATE_OK), "OK");
  EXPECT_STREQ(pex::runtime::daemon_state_name(pex::daemon_status_t::STATE_DEGRADED), "DEGRADED");
  EXPECT_STREQ(pex::runtime::daemon_state_name(pex::daemon_status_t::STATE_ERROR), "ERROR");
  EXPECT_STREQ(pex::runtime::daemon_state_name(pex::daemon_status_t::STATE_STOPPING), "STOPPING");
  EXPECT_STREQ(pex::runtime::daemon_state_name(42), "UNKNOWN");

  const std::string path = (std::filesystem::temp_directory_path() / ("pex_notify_" + std::to_string(::getpid()))).string();
  ::unlink(path.c_str());
  const int sock = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(sock, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  ASSERT_EQ(::bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ::setenv("NOTIFY_SOCKET", path.c_str(), 1);
  std::string journal;
  {
    const pex::runtime::LogCapture log;
    {
      Node node(NodeOptions{"t", kUrl, false, "", 1.0});
      node.set_state(pex::daemon_status_t::STATE_DEGRADED, "no scans for 2.0 s");
    }
    journal = log.text();
  }
  ::unsetenv("NOTIFY_SOCKET");
  std::string notified;
  char buf[512];
  for (ssize_t n; (n = ::recv(sock, buf, sizeof buf, MSG_DONTWAIT)) > 0;) notified += std::string(buf, n) + "\n";
  ::close(sock);
  ::unlink(path.c_str());
  EXPECT_NE(journal.find("state DEGRADED: no scans for 2.0 s"), std::string::npos) << journal;
  EXPECT_NE(notified.find("STATUS=DEGRADED (no scans for 2.0 s), in "), std::string::npos) << notified;
  EXPECT_EQ(notified.find("STATUS=state "), std::string::npos) << notified;
}
