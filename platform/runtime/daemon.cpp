#include "runtime/daemon.hpp"

#include <signal.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include <spdlog/sinks/stdout_color_sinks.h>

#include "cli/command_line.hpp"
#include "runtime/log_file_error.hpp"

namespace pex::runtime {

namespace {

// The options every daemon gets, filled by the command line.
struct CommonArgs {
  std::vector<std::string> config_paths;  // the layers, lowest first
  std::string lcm_url;
  std::string log_level = "info";
  std::vector<std::string> replay_logs;
  std::string replay_out;
};

// Blocks SIGINT/SIGTERM for normal delivery and returns a signalfd for them, so
// the poll loop sees a stop request as an ordinary readable fd (no handler races).
int make_signal_fd() {
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGINT);
  sigaddset(&mask, SIGTERM);
  sigprocmask(SIG_BLOCK, &mask, nullptr);
  return signalfd(-1, &mask, SFD_CLOEXEC | SFD_NONBLOCK);
}
}  // namespace

RuntimeOptions load_runtime_options(ConfigReader& config, bool is_clock_source) {
  RuntimeOptions o;
  o.heartbeat_period_ms = config.get<int>("heartbeat_period_ms", o.heartbeat_period_ms, in_range(10, 60'000));
  const std::string clock = config.get<std::string>("clock", "system", one_of({"system", "sim"}));
  if (clock == "sim" && is_clock_source)
    config.fail("clock", "this daemon publishes the simulated clock and runs on the system's: must be \"system\", got \"sim\"");
  o.clock = clock == "sim" ? ClockSource::kSim : ClockSource::kSystem;
  return o;
}

int run_daemon(int argc, char** argv, const DaemonInfo& info, const DaemonSetup& setup) {
  // The program's name as installed: "polygon_mapper" -> "pex-polygon-mapper".
  std::string program = "pex-" + info.name;
  std::replace(program.begin(), program.end(), '_', '-');
  CLI::App app{info.description};
  CommonArgs args;
  app.add_option("--config", args.config_paths,
                 "TOML configuration file; several: layered, each key from the last file that sets it "
                 "(default: built-in defaults)")
      ->check(CLI::ExistingFile);
  bool print_config = false;
  app.add_flag("--print-config", print_config,
               "print the effective configuration (each key, its value, and where it came from: default or "
               "FILE:LINE) and exit");
  app.add_option("--lcm-url", args.lcm_url,
                 "LCM URL, e.g. udpm://239.255.76.67:7667?ttl=0 (default: $LCM_DEFAULT_URL or LCM's)");
  app.add_option("--log-level", args.log_level, "trace, debug, info, warn, error, critical, off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
  if (info.supports_replay) {
    app.add_option("--log", args.replay_logs,
                   "replay this LCM log through the same handlers, as fast as possible, then exit "
                   "(several: merged by event time); a log that cannot be opened exits 66, a damaged one 65");
    app.add_option("--out", args.replay_out, "with --log: write what is published to this LCM log");
  }
  if (info.add_options) info.add_options(app);
  if (const auto code = cli::parse_command_line(app, program, argc, argv)) return *code;

  auto logger = spdlog::stderr_color_mt(info.name);
  logger->set_pattern("%Y-%m-%dT%H:%M:%S.%e %n[%P] %^%l%$: %v");
  spdlog::set_default_logger(logger);
  spdlog::set_level(spdlog::level::from_str(args.log_level));

  if (print_config) {
    try {
      ConfigReader config = ConfigReader::from_files(args.config_paths);
      load_runtime_options(config, info.is_clock_source);
      if (info.load_options) info.load_options(config);
      config.finish();
      std::printf("# %s --print-config: defaults < %s (each key: the last that sets it)\n%s", program.c_str(),
                  args.config_paths.empty() ? "no file" : config.origin().c_str(), config.effective_toml().c_str());
      return exit_code::kOk;
    } catch (const ConfigError& e) {
      spdlog::critical("config error: {}", e.what());
      return exit_code::kConfig;
    }
  }

  const bool offline = !args.replay_logs.empty();
  const int signal_fd = make_signal_fd();
  try {
    ConfigReader config = ConfigReader::from_files(args.config_paths);
    const RuntimeOptions every_daemon = load_runtime_options(config, info.is_clock_source);
    const bool sim_clock = every_daemon.clock == ClockSource::kSim;
    if (sim_clock && offline) spdlog::info("clock = \"sim\" is ignored in replay: the log's time is the clock");
    Node node(NodeOptions{info.name, args.lcm_url, offline, args.replay_out, every_daemon.heartbeat_period_ms * 1e-3,
                          every_daemon.clock});
    node.set_signal_fd(signal_fd);
    setup(node, config);
    config.finish();
    spdlog::info("started ({}; config {})",
                 offline ? "replay of " + std::to_string(args.replay_logs.size()) + " log(s)"
                         : std::string("live, ") + (sim_clock ? "sim" : "system") + " clock",
                 config.origin());
    if (offline) {
      const int64_t events = node.replay_logs(args.replay_logs);
      spdlog::info("replayed {} events, {} rejected, {} errors", events, node.msgs_rejected(),
                   node.errors());
    } else {
      node.run();
      spdlog::info("stopped");
    }
  } catch (const ConfigError& e) {
    spdlog::critical("config error: {}", e.what());
    return exit_code::kConfig;
  } catch (const LogFileError& e) {
    spdlog::critical("input: {}", e.what());
    spdlog::default_logger()->flush();
    return e.kind() == LogFileError::Kind::kCannotOpen ? exit_code::kNoInput : exit_code::kDataError;
  } catch (const Unavailable& e) {
    spdlog::critical("unavailable: {}", e.what());
    return exit_code::kUnavailable;
  } catch (const std::exception& e) {
    spdlog::critical("fatal: {}", e.what());
    return exit_code::kFatal;
  }
  spdlog::default_logger()->flush();
  return exit_code::kOk;
}

}  // namespace pex::runtime
