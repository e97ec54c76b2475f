#include "harness.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "runtime/channels.hpp"

namespace fs = std::filesystem;

namespace pex::testing {

bool in_private_netns(std::string* why) {
  // /proc/self/net is this process's namespace (/sys/class/net is the one sysfs
  // was mounted in, so it would show the host's interfaces).
  std::ifstream dev("/proc/self/net/dev");
  std::string line;
  std::vector<std::string> others;
  int lines = 0;
  while (std::getline(dev, line)) {
    if (++lines <= 2) continue;  // two header lines
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    name.erase(0, name.find_first_not_of(' '));
    if (name != "lo") others.push_back(name);
  }
  if (lines > 2 && others.empty()) return true;
  if (why) {
    *why = lines <= 2 ? "cannot read /proc/self/net/dev" : "network interfaces besides lo:";
    for (const auto& o : others) *why += " " + o;
    *why += " (run through scripts/netns-run; register the test with NETNS)";
  }
  return false;
}

std::string bin_path(const std::string& program) { return std::string(PEX_BINARY_DIR) + "/bin/" + program; }
std::string source_path(const std::string& relative) { return std::string(PEX_SOURCE_DIR) + "/" + relative; }
std::string shared_path(const std::string& relative) { return std::string(PEX_SHARED_DIR) + "/" + relative; }

std::string make_temp_dir(const std::string& tag) {
  std::string tmpl = (fs::temp_directory_path() / ("pex_" + tag + "_XXXXXX")).string();
  if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed for " + tmpl);
  return tmpl;
}

bool keep_test_dir(bool failed) { return failed || std::getenv("PEX_KEEP_LOGS") != nullptr; }

ScratchDir::~ScratchDir() {
  if (keep_test_dir(::testing::Test::HasFailure())) return;
  std::error_code ignored;  // a folder that cannot go is litter, not a failure
  fs::remove_all(path_, ignored);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
}

Process::Process(std::vector<std::string> argv, std::string log_path)
    : argv_(std::move(argv)), log_path_(std::move(log_path)) {
  std::string why;
  if (!in_private_netns(&why)) throw std::runtime_error("refusing to start " + argv_.front() + ": " + why);
  const int log_fd = ::open(log_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot open " + log_path_);
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ == 0) {
    // The daemon dies with the test: a test that aborts (a failed sanitizer
    // check, a crash) runs no destructor, and its daemons went on for ever
    // (117 of them once, filling the machine's memory). The signal follows
    // the forking *thread*: start daemons from the test's own thread.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the test died before prctl
    ::dup2(log_fd, 1);
    ::dup2(log_fd, 2);
    // The daemons block SIGTERM themselves for their signalfd; start clean.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    std::vector<char*> args;
    for (auto& a : argv_) args.push_back(a.data());
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  ::close(log_fd);
  if (pid_ < 0) throw std::runtime_error("fork failed");
}

Process::~Process() {
  if (pid_ > 0 && exit_code_ == -2) kill_hard();
}

bool Process::running() {
  if (exit_code_ != -2) return false;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == 0) return true;
  exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return false;
}

int Process::wait(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (running()) {
    if (std::chrono::steady_clock::now() > deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return exit_code_;
}

int Process::stop(std::chrono::milliseconds timeout) {
  if (!running()) return exit_code_;
  ::kill(pid_, SIGTERM);
  const int code = wait(timeout);
  if (code == -1) {
    kill_hard();
    return -1;
  }
  return code;
}

void Process::kill_hard() {
  if (!running()) return;
  ::kill(pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  exit_code_ = 128 + SIGKILL;
}

RunResult run_to_completion(const std::vector<std::string>& argv, std::chrono::milliseconds timeout) {
  const std::string dir = make_temp_dir("run");
  const std::string log = dir + "/out.log";
  int code;
  {
    Process p(argv, log);
    code = p.wait(timeout);
    if (code == -1) p.kill_hard();
  }
  RunResult r{code, read_file(log)};
  fs::remove_all(dir);
  return r;
}

Bus::Bus() : lcm_(kTestLcmUrl) {
  std::string why;
  if (!in_private_netns(&why)) throw std::runtime_error("refusing to open the test bus: " + why);
  if (!lcm_.good()) throw std::runtime_error(std::string("cannot open LCM at ") + kTestLcmUrl);
  // A plain function, not &Bus::on_any: GCC's UBSan misreads LCM 1.3's
  // member-pointer dispatch as a member access at address 0x1 (every test
  // on this bus failed the sanitizer build; tools/mission/main.cpp too).
  lcm_.subscribeFunction(
      ".*", +[](const lcm::ReceiveBuffer* rb, const std::string& channel, Bus* bus) { bus->on_any(rb, channel); },
      this);
}

void Bus::on_any(const lcm::ReceiveBuffer* rb, const std::string& channel) {
  ++counts_[channel];
  if (channel == pex::runtime::channels::kDaemonStatus) {
    pex::daemon_status_t s{};
    if (s.decode(rb->data, 0, static_cast<int>(rb->data_size)) == static_cast<int>(rb->data_size))
      status_[s.name] = s;
  }
  if (auto it = typed_.find(channel); it != typed_.end())
    for (auto& fn : it->second) fn(rb);
}

bool Bus::spin_until(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return done();
    lcm_.handleTimeout(static_cast<int>(std::min<int64_t>(left.count(), 50)));
  }
  return true;
}

void Bus::spin_for(std::chrono::milliseconds duration) {
  spin_until([] { return false; }, duration);
}

int Bus::count(const std::string& channel) const {
  auto it = counts_.find(channel);
  return it == counts_.end() ? 0 : it->second;
}

bool Bus::all_ok(const std::vector<std::string>& names) const {
  return std::all_of(names.begin(), names.end(), [&](const std::string& n) {
    auto it = status_.find(n);
    return it != status_.end() && it->second.state == pex::daemon_status_t::STATE_OK;
  });
}

std::int64_t counter_of(const pex::daemon_status_t& status, const std::string& name) {
  for (int i = 0; i < status.ncounters; ++i)
    if (status.counter_names[static_cast<std::size_t>(i)] == name) return status.counter_values[static_cast<std::size_t>(i)];
  return -1;
}

std::string program_of(const std::string& daemon_name) {
  std::string p = "pex-" + daemon_name;
  std::replace(p.begin(), p.end(), '_', '-');
  return p;
}

std::string sim_config_of(const std::string& daemon_name) {
  return source_path("config/" + daemon_name + ".toml");
}

std::unique_ptr<Process> start_daemon(const std::string& name, const std::string& log_dir,
                                      std::vector<std::string> extra_args,
                                      const std::string& config_path) {
  std::vector<std::string> argv = {bin_path(program_of(name)), "--config",
                                   config_path.empty() ? sim_config_of(name) : config_path,
                                   "--lcm-url", kTestLcmUrl};
  argv.insert(argv.end(), extra_args.begin(), extra_args.end());
  return std::make_unique<Process>(argv, log_dir + "/" + name + ".log");
}

}  // namespace pex::testing

#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/mission_cmd_t.hpp>
#include <pex/sim_clock_t.hpp>
#include <pex/laser_scan_t.hpp>
#include <pex/odometry_t.hpp>
#include <pex/polygon_map_t.hpp>
#include <pex/pose_t.hpp>
#include <pex/slam_update_t.hpp>
#include <pex/velocity_cmd_t.hpp>

namespace pex::testing {

namespace {
template <class Msg>
std::string try_decode(const void* data, int size) {
  Msg m{};
  const int used = m.decode(data, 0, size);
  if (used != size) return "decode as " + std::string(Msg::getTypeName()) + " used " +
                           std::to_string(used) + " of " + std::to_string(size) + " bytes";
  return "";
}
}  // namespace

std::string decode_registered(const std::string& channel, const void* data, int size) {
  const auto* info = pex::runtime::channels::find(channel);
  if (!info) return "channel " + channel + " is not in the registry";
  const std::string_view t = info->type;
  if (t == "pex.laser_scan_t") return try_decode<pex::laser_scan_t>(data, size);
  if (t == "pex.odometry_t") return try_decode<pex::odometry_t>(data, size);
  if (t == "pex.velocity_cmd_t") return try_decode<pex::velocity_cmd_t>(data, size);
  if (t == "pex.slam_update_t") return try_decode<pex::slam_update_t>(data, size);
  if (t == "pex.pose_t") return try_decode<pex::pose_t>(data, size);
  if (t == "pex.polygon_map_t") return try_decode<pex::polygon_map_t>(data, size);
  if (t == "pex.explore_state_t") return try_decode<pex::explore_state_t>(data, size);
  if (t == "pex.daemon_status_t") return try_decode<pex::daemon_status_t>(data, size);
  if (t == "pex.sim_clock_t") return try_decode<pex::sim_clock_t>(data, size);
  if (t == "pex.mission_cmd_t") return try_decode<pex::mission_cmd_t>(data, size);
  return "no decoder for type " + std::string(t);
}

std::string logs_of(const std::vector<Process*>& processes) {
  std::string out;
  for (Process* p : processes) out += "--- " + p->name() + "\n" + p->output() + "\n";
  return out;
}

pex::velocity_cmd_t velocity_command(double v, double omega, const std::string& source) {
  pex::velocity_cmd_t c{};
  c.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                std::chrono::system_clock::now().time_since_epoch())
                .count();
  c.v = v;
  c.omega = omega;
  c.source = source;
  return c;
}

bool drive_until(Bus& bus, double v, const std::function<bool()>& done, const std::string& source) {
  return bus.spin_until(
      [&] {
        bus.publish(std::string(pex::runtime::channels::kBaseCmd), velocity_command(v, 0.0, source));
        bus.spin_for(std::chrono::milliseconds(50));
        return done();
      },
      std::chrono::seconds(60));
}

}  // namespace pex::testing
