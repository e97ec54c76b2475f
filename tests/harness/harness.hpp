#pragma once
// Test harness for integration tests: real daemon processes on a real LCM bus.
//
// Tests using it are registered with pex_add_gtest(... NETNS), so each runs in a
// private network namespace (scripts/netns-run); the harness refuses to start
// anything when it finds another interface than loopback, so no test can put
// LCM traffic on a real network.
#include <sys/types.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <pex/daemon_status_t.hpp>
#include <pex/velocity_cmd_t.hpp>

namespace pex::testing {

inline constexpr const char* kTestLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

// True if this process's network namespace has no interface but `lo`.
bool in_private_netns(std::string* why = nullptr);

std::string bin_path(const std::string& program);        // build/bin/<program>
std::string source_path(const std::string& relative);    // repository file
std::string shared_path(const std::string& relative);    // ../shared file
std::string make_temp_dir(const std::string& tag);       // fresh folder under $TMPDIR
// Whether a test's folder stays after it: when the test failed, or with
// PEX_KEEP_LOGS set (its daemons' logs are what there is to read).
bool keep_test_dir(bool failed);

// A fresh folder under $TMPDIR that goes with its files unless keep_test_dir
// (the test that made it failed, or PEX_KEEP_LOGS).
// For tests that return early on an ASSERT, which skips a remove_all at the end.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag) : path_(make_temp_dir(tag)) {}
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};
std::string read_file(const std::string& path);
void write_file(const std::string& path, const std::string& text);

// A child process with stdout and stderr captured to a log file.
class Process {
 public:
  Process(std::vector<std::string> argv, std::string log_path);
  ~Process();  // SIGKILLs a process still running
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  bool running();
  // SIGTERM, then waits; returns the exit code, 128+signal if killed by one,
  // or -1 if it had to be SIGKILLed after `timeout`.
  int stop(std::chrono::milliseconds timeout = std::chrono::seconds(5));
  // Waits for exit without signalling; -1 on timeout.
  int wait(std::chrono::milliseconds timeout);
  void kill_hard();
  std::string output() const { return read_file(log_path_); }
  const std::string& name() const { return argv_.front(); }

 private:
  std::vector<std::string> argv_;
  std::string log_path_;
  pid_t pid_ = -1;
  int exit_code_ = -2;  // -2: not yet reaped
};

struct RunResult {
  int exit_code;       // as Process::stop()/wait()
  std::string output;  // stdout + stderr
};
// Runs a command to completion (SIGKILL after `timeout`).
RunResult run_to_completion(const std::vector<std::string>& argv,
                            std::chrono::milliseconds timeout = std::chrono::seconds(10));

// The test's own LCM endpoint: watches every channel.
class Bus {
 public:
  Bus();
  lcm::LCM& lcm() { return lcm_; }

  // Handles traffic until `done()` or `timeout`; returns done().
  bool spin_until(const std::function<bool()>& done, std::chrono::milliseconds timeout);
  void spin_for(std::chrono::milliseconds duration);

  template <class Msg>
  void on(const std::string& channel, std::function<void(const Msg&)> fn) {
    typed_[channel].push_back([fn](const lcm::ReceiveBuffer* rb) {
      Msg m{};
      if (m.decode(rb->data, 0, static_cast<int>(rb->data_size)) == static_cast<int>(rb->data_size))
        fn(m);
    });
  }
  template <class Msg>
  void publish(const std::string& channel, const Msg& msg) {
    lcm_.publish(channel, &msg);
  }

  // Newest DAEMON_STATUS of each daemon by name, and message counts per channel.
  const std::map<std::string, pex::daemon_status_t>& status() const { return status_; }
  int count(const std::string& channel) const;
  // True once every named daemon's newest status has state OK.
  bool all_ok(const std::vector<std::string>& names) const;

 private:
  void on_any(const lcm::ReceiveBuffer* rb, const std::string& channel);
  lcm::LCM lcm_;
  std::map<std::string, pex::daemon_status_t> status_;
  std::map<std::string, int> counts_;
  std::map<std::string, std::vector<std::function<void(const lcm::ReceiveBuffer*)>>> typed_;
};

// The shipped config of a daemon for the simulator deployment, config/<name>.toml
// (config/robot/<name>.toml holds the robot's where it differs: never started
// by tests, since it names real devices and addresses).
std::string sim_config_of(const std::string& daemon_name);

// A daemon of the set on the test bus, started with `config_path` (default:
// sim_config_of(name)); its output goes to <log_dir>/<name>.log.
std::unique_ptr<Process> start_daemon(const std::string& name, const std::string& log_dir,
                                      std::vector<std::string> extra_args = {},
                                      const std::string& config_path = "");

// Every process's name and output, for a failing test's message.
std::string logs_of(const std::vector<Process*>& processes);

// A counter of a DAEMON_STATUS by name; -1 if the status has none of that name.
std::int64_t counter_of(const pex::daemon_status_t& status, const std::string& name);

// A BASE_CMD stamped with the wall clock, as a test drives the robot.
pex::velocity_cmd_t velocity_command(double v, double omega, const std::string& source);

// Drives as an explorer would, a BASE_CMD of v (straight on) every 50 ms,
// until `done` (false after 60 s of wall time: only a hung set gets there).
bool drive_until(Bus& bus, double v, const std::function<bool()>& done, const std::string& source);

// "polygon_mapper" -> "pex-polygon-mapper"
std::string program_of(const std::string& daemon_name);

inline const std::vector<std::string> kAllDaemons = {"lidar_reader", "base_driver", "slam",
                                                      "polygon_mapper", "explorer", "sim"};

}  // namespace pex::testing

namespace pex::testing {
// Decodes `data` as the type the channel registry names for `channel`.
// Returns "" on success, else why it failed (unknown channel, bad bytes).
std::string decode_registered(const std::string& channel, const void* data, int size);
}  // namespace pex::testing
