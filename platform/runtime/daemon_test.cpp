// run_daemon's `clock` key: "system" (default) or "sim", anything else a
// config error (exit 78), and "sim" refused for the daemon that is the clock.
#include "runtime/daemon.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>

using pex::runtime::ClockSource;
using pex::runtime::DaemonInfo;
using pex::runtime::run_daemon;

namespace {

class DaemonClock : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("pex_daemon_test_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Runs a daemon whose setup records the node's clock and stops it at once.
  // memq:// is LCM's in-process queue: no network is touched.
  int run(const std::string& toml, bool is_clock_source = false) {
    const std::string path = (dir_ / "d.toml").string();
    std::ofstream(path) << toml;
    // spdlog loggers are registered by name, once per process: one name per run.
    static int runs = 0;
    DaemonInfo info{"clocktest" + std::to_string(++runs), "test daemon"};
    info.is_clock_source = is_clock_source;
    std::vector<std::string> args = {"pex-test", "--config", path, "--lcm-url", "memq://", "--log-level", "off"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    seen_.reset();
    return run_daemon(static_cast<int>(argv.size()), argv.data(), info,
                      [this](pex::runtime::Node& node, pex::runtime::ConfigReader&) {
                        seen_ = node.clock_source();
                        node.request_stop();
                      });
  }

  std::filesystem::path dir_;
  std::optional<ClockSource> seen_;
};

}  // namespace

TEST_F(DaemonClock, DefaultIsTheSystemClock) {
  EXPECT_EQ(run("heartbeat_period_ms = 1000\n"), 0);
  EXPECT_EQ(seen_, ClockSource::kSystem);
}

TEST_F(DaemonClock, SimAndSystemAreAccepted) {
  EXPECT_EQ(run("clock = \"sim\"\n"), 0);
  EXPECT_EQ(seen_, ClockSource::kSim);
  EXPECT_EQ(run("clock = \"system\"\n"), 0);
  EXPECT_EQ(seen_, ClockSource::kSystem);
}

TEST_F(DaemonClock, AnythingElseIsAConfigError) {
  EXPECT_EQ(run("clock = \"wall\"\n"), pex::runtime::exit_code::kConfig);
  EXPECT_EQ(seen_, std::nullopt);
  EXPECT_EQ(run("clock = 1\n"), pex::runtime::exit_code::kConfig);
}

TEST_F(DaemonClock, TheClockSourceCannotRunOnItsOwnClock) {
  EXPECT_EQ(run("clock = \"sim\"\n", /*is_clock_source=*/true), pex::runtime::exit_code::kConfig);
  EXPECT_EQ(seen_, std::nullopt);
  EXPECT_EQ(run("clock = \"system\"\n", /*is_clock_source=*/true), 0);
}
