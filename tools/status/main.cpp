// pex-status: listens to DAEMON_STATUS for a while and prints one line per
// daemon — the quick "is the set healthy?" look on a robot with no screen.
// Exit code 0 if every daemon named with --expect reported STATE_OK, else 1.
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <pex/daemon_status_t.hpp>

#include "runtime/channels.hpp"

namespace {

const char* state_name(int8_t s) {
  switch (s) {
    case pex::daemon_status_t::STATE_STARTING: return "STARTING";
    case pex::daemon_status_t::STATE_OK: return "OK";
    case pex::daemon_status_t::STATE_DEGRADED: return "DEGRADED";
    case pex::daemon_status_t::STATE_ERROR: return "ERROR";
    case pex::daemon_status_t::STATE_STOPPING: return "STOPPING";
    default: return "?";
  }
}

void on_status(const lcm::ReceiveBuffer* rb, const std::string&,
               std::map<std::string, pex::daemon_status_t>* latest) {
  pex::daemon_status_t s{};
  if (s.decode(rb->data, 0, static_cast<int>(rb->data_size)) == static_cast<int>(rb->data_size))
    (*latest)[s.name] = s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Print the health of the running daemons (DAEMON_STATUS)", "pex-status"};
  std::string url;
  double seconds = 2.5;
  std::vector<std::string> expect;
  bool counters = false;
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL or LCM's)");
  app.add_option("--seconds", seconds, "how long to listen")->check(CLI::PositiveNumber);
  app.add_option("--expect", expect, "daemon names that must be OK (exit 1 otherwise)");
  app.add_flag("--counters", counters, "also print each daemon's own counters");
  CLI11_PARSE(app, argc, argv);

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "pex-status: cannot open LCM at '%s'\n", url.c_str());
    return 1;
  }
  std::map<std::string, pex::daemon_status_t> latest;
  lcm.subscribeFunction(std::string(pex::runtime::channels::kDaemonStatus), &on_status, &latest);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(50);

  std::printf("%-16s %-9s %7s %9s %9s %8s %7s  %s\n", "daemon", "state", "pid", "in", "out",
              "rejected", "errors", "last error");
  for (const auto& [name, s] : latest) {
    std::printf("%-16s %-9s %7d %9lld %9lld %8lld %7lld  %s\n", name.c_str(), state_name(s.state),
                s.pid, static_cast<long long>(s.msgs_in), static_cast<long long>(s.msgs_out),
                static_cast<long long>(s.msgs_rejected), static_cast<long long>(s.errors),
                s.last_error.c_str());
    if (counters)
      for (int i = 0; i < s.ncounters; ++i)
        std::printf("%16s   %s = %lld\n", "", s.counter_names[i].c_str(),
                    static_cast<long long>(s.counter_values[i]));
  }
  int missing = 0;
  for (const auto& name : expect) {
    auto it = latest.find(name);
    if (it == latest.end()) {
      std::printf("%-16s no status heard\n", name.c_str());
      ++missing;
    } else if (it->second.state != pex::daemon_status_t::STATE_OK) {
      ++missing;
    }
  }
  return missing == 0 ? 0 : 1;
}
