// The whole daemon set on a real LCM bus (private network namespace).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "harness.hpp"

using namespace pex::testing;
using namespace std::chrono_literals;

TEST(DaemonSet, AllSixStartHealthyAndStopCleanlyOnTheSimulator) {
  Bus bus;
  const std::string logs = make_temp_dir("set");
  std::vector<std::unique_ptr<Process>> set;
  // The simulator first: the hardware daemons talk to it over TCP and CAN.
  set.push_back(start_daemon("sim", logs));
  for (const auto& name : kAllDaemons)
    if (name != "sim") set.push_back(start_daemon(name, logs));

  // The budget only ends a hung set; healthy sets get there in about a second.
  const bool healthy = bus.spin_until([&] { return bus.all_ok(kAllDaemons); }, 60s);
  std::string report;
  for (const auto& name : kAllDaemons) {
    auto it = bus.status().find(name);
    report += name + ": " +
              (it == bus.status().end() ? "no status"
                                        : "state " + std::to_string(it->second.state) + " '" +
                                              it->second.last_error + "'") + "\n";
  }
  for (auto& p : set) report += "--- " + p->name() + "\n" + p->output();
  EXPECT_TRUE(healthy) << report;

  for (auto& p : set) {
    EXPECT_TRUE(p->running()) << p->name() << " exited early:\n" << p->output();
    EXPECT_EQ(p->stop(5s), 0) << p->name() << ":\n" << p->output();
  }
  // Each announced its stop on the bus.
  bus.spin_for(200ms);
  for (const auto& name : kAllDaemons) {
    auto it = bus.status().find(name);
    ASSERT_NE(it, bus.status().end()) << name;
    EXPECT_EQ(it->second.state, +pex::daemon_status_t::STATE_STOPPING) << name;
  }
  std::filesystem::remove_all(logs);
}

TEST(DaemonSet, HeartbeatCountsAndNamesAreRight) {
  Bus bus;
  const std::string logs = make_temp_dir("hb");
  auto explorer = start_daemon("explorer", logs);
  // Three heartbeats (1 Hz), all from pex-explorer's pid.
  std::vector<pex::daemon_status_t> seen;
  bus.on<pex::daemon_status_t>("DAEMON_STATUS", [&](const pex::daemon_status_t& s) { seen.push_back(s); });
  bus.spin_until([&] { return seen.size() >= 3; }, 60s);
  ASSERT_GE(seen.size(), 3u) << explorer->output();
  for (const auto& s : seen) {
    EXPECT_EQ(s.name, "explorer");
    EXPECT_EQ(s.pid, explorer->pid());
    EXPECT_EQ(s.msgs_rejected, 0);
  }
  EXPECT_GT(seen.back().msgs_out, seen.front().msgs_out);
  EXPECT_EQ(explorer->stop(), 0);
  std::filesystem::remove_all(logs);
}

TEST(DaemonSet, RefusesToRunOutsideAPrivateNamespace) {
  // We are inside one (NETNS tests): only loopback.
  std::string why;
  ASSERT_TRUE(in_private_netns(&why)) << why;
  // Another interface in this (private) namespace, as a host's network would
  // show one: a bridge, which carries nothing and needs no kernel module. The
  // check must see it, and the harness must refuse to start a daemon.
  const RunResult added = run_to_completion({"/usr/sbin/ip", "link", "add", "pexbr0", "type", "bridge"});
  ASSERT_EQ(added.exit_code, 0) << added.output;
  EXPECT_FALSE(in_private_netns(&why));
  EXPECT_NE(why.find("pexbr0"), std::string::npos) << why;
  const std::string logs = make_temp_dir("netns");
  EXPECT_THROW(start_daemon("explorer", logs), std::runtime_error);
  // Not through the harness, which now refuses to start anything.
  EXPECT_EQ(std::system("/usr/sbin/ip link del pexbr0"), 0);
  EXPECT_TRUE(in_private_netns(&why)) << why;
  std::filesystem::remove_all(logs);
}
