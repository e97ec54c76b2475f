#pragma once
// run_daemon(): the whole life of a daemon around its own setup function.
//
//   args (CLI11) -> logging (spdlog) -> config (TOML) -> Node -> setup(node, config)
//   -> unknown config keys rejected -> READY=1 -> poll loop until SIGTERM -> flush.
//
// `--config FILE` may be given several times: layered, each key from the last file that
// sets it (runtime/config.hpp). `--print-config` prints the effective configuration,
// every key with its value and source (default or FILE:LINE), as TOML, and exits 0
// (78 for a bad config, as a start would).
//
// Exit codes, documented for systemd (RestartPreventExitStatus=64 78):
//   0   clean stop (SIGINT/SIGTERM, or the end of a replayed log)
//   1   fatal error at run time, or at start for a reason not listed below
//   64  bad command line (EX_USAGE)
//   69  a device or service is not there (EX_UNAVAILABLE), e.g. no CAN interface
//   78  bad configuration (EX_CONFIG): unknown key, wrong type, value out of range
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "runtime/config.hpp"
#include "runtime/node.hpp"

namespace pex::runtime {

namespace exit_code {
inline constexpr int kOk = 0;
inline constexpr int kFatal = 1;
inline constexpr int kUsage = 64;
inline constexpr int kDataError = 65;  // an input file's content is broken (a damaged or foreign log)
inline constexpr int kNoInput = 66;    // an input file cannot be opened
inline constexpr int kUnavailable = 69;
inline constexpr int kConfig = 78;
}  // namespace exit_code

// Thrown from setup when a device the daemon needs is missing (exit 69).
class Unavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DaemonInfo {
  std::string name;         // "lidar_reader": status name, log prefix
  std::string description;  // one line for --help
  // Adds `--log IN.lcm` (replay a log through the same handlers, as fast as
  // possible, then exit; given several times, the logs are merged by event
  // time) and `--out OUT.lcm` (write what it publishes).
  bool supports_replay = false;
  // Daemon-specific command-line options, registered before parsing.
  std::function<void(CLI::App&)> add_options = {};
  // The daemon publishes SIM_CLOCK (pex-sim): it cannot run on it, so
  // `clock = "sim"` in its config is a config error.
  bool is_clock_source = false;
  // Reads the daemon's typed options (its load_options) and nothing else: what
  // `--print-config` runs instead of setup, so every key is read as the daemon reads it.
  std::function<void(ConfigReader&)> load_options = {};
};

// setup() reads its typed options from `config` and wires handlers into `node`.
// It may throw ConfigError (exit 78), Unavailable (exit 69) or anything else (exit 1).
using DaemonSetup = std::function<void(Node& node, ConfigReader& config)>;

int run_daemon(int argc, char** argv, const DaemonInfo& info, const DaemonSetup& setup);

// The keys every daemon's config has, read by run_daemon before setup. A test
// of a shipped config reads them through this, as the daemon does, before finish().
struct RuntimeOptions {
  int heartbeat_period_ms = 1000;            // DAEMON_STATUS period
  ClockSource clock = ClockSource::kSystem;  // `clock`: "system" | "sim"
};
// Throws ConfigError; with `is_clock_source` (pex-sim), clock = "sim" is one.
RuntimeOptions load_runtime_options(ConfigReader& config, bool is_clock_source = false);

}  // namespace pex::runtime
