// pex-status: listens to DAEMON_STATUS for a while and prints one line per
// daemon — the quick "is the set healthy?" look on a robot with no screen.
// Exit code 0 if every daemon named with --expect reported STATE_OK, else 1.
// With --follow-mission it follows the exploration mission instead.
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <lcm/lcm-cpp.hpp>
#include <pex/daemon_status_t.hpp>
#include <pex/explore_state_t.hpp>

#include "cli/command_line.hpp"
#include "planning/mission.hpp"
#include "runtime/channels.hpp"
#include "runtime/daemon_state.hpp"

namespace {

void on_status(const lcm::ReceiveBuffer* rb, const std::string&,
               std::map<std::string, pex::daemon_status_t>* latest) {
  pex::daemon_status_t s{};
  if (s.decode(rb->data, 0, static_cast<int>(rb->data_size)) == static_cast<int>(rb->data_size))
    (*latest)[s.name] = s;
}

struct LatestState {
  pex::explore_state_t state{};
  std::chrono::steady_clock::time_point heard{};  // when `state` arrived
};

void on_explore(const lcm::ReceiveBuffer* rb, const std::string&, LatestState* latest) {
  pex::explore_state_t s{};
  if (s.decode(rb->data, 0, static_cast<int>(rb->data_size)) == static_cast<int>(rb->data_size)) {
    latest->state = s;
    latest->heard = std::chrono::steady_clock::now();
  }
}

const char* phase_name(int8_t p) {
  if (p < 0 || p > static_cast<int8_t>(pex::planning::Phase::kStopped)) return "?";
  return pex::planning::to_string(static_cast<pex::planning::Phase>(p));
}

// The mission is over on its own, or by command.
bool mission_over(int8_t p) {
  using pex::planning::Phase;
  if (p < 0) return false;
  const auto phase = static_cast<Phase>(p);
  return pex::planning::is_finished(phase) || phase == Phase::kHome || phase == Phase::kStopped;
}

// Follows EXPLORE_STATE until the mission is over or has run `seconds` of its
// own clock (the explorer's: simulated time with clock = "sim", so the limit
// means the same at any simulator speed), printing progress every `every_s`
// of wall time. `wall_limit_s` guards against a mission clock that stands
// still; `state_timeout_s` against an explorer that is not there (never
// started, refused its config, died): no EXPLORE_STATE for that long, from
// the start or since the last one, ends the follow at once. Exit 0 on DONE,
// 2 on DONE_WITH_UNREACHABLE, 3 when EXPLORE_STATE stopped, 1 otherwise.
int follow_mission(lcm::LCM& lcm, double seconds, double every_s, double wall_limit_s, double state_timeout_s) {
  LatestState heard;
  pex::explore_state_t& latest = heard.state;
  latest.phase = -1;
  lcm.subscribeFunction(std::string(pex::runtime::channels::kExploreState), &on_explore, &heard);
  const auto start = std::chrono::steady_clock::now();
  heard.heard = start;
  auto next_print = start;
  while (true) {
    lcm.handleTimeout(100);
    const auto now = std::chrono::steady_clock::now();
    const double wall = std::chrono::duration<double>(now - start).count();
    const double silent = std::chrono::duration<double>(now - heard.heard).count();
    if (silent >= state_timeout_s) {
      std::printf("no EXPLORE_STATE for %g s (wall clock)%s: is the explorer running?\n", state_timeout_s,
                  latest.phase < 0 ? " since the start" : "");
      std::fflush(stdout);
      return 3;
    }
    const double t = latest.phase < 0 ? 0.0 : latest.mission_time_s;
    const bool over = mission_over(latest.phase);
    const bool out_of_time = t >= seconds || wall >= wall_limit_s;
    if (now >= next_print || over || out_of_time) {
      if (latest.phase < 0)
        std::printf("%6.0f s  no EXPLORE_STATE yet\n", t);
      else
        std::printf("%6.0f s  %-9s explored %7.1f m2  driven %6.1f m  goals %3d  candidates %3d  %s\n", t,
                    phase_name(latest.phase), latest.explored_area_m2, latest.distance_travelled_m,
                    latest.goals_reached, latest.goal_candidates, latest.status.c_str());
      std::fflush(stdout);
      next_print = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                             std::chrono::duration<double>(every_s));
    }
    if (over) {
      if (latest.phase == pex::explore_state_t::PHASE_DONE) return 0;
      return latest.phase == pex::explore_state_t::PHASE_DONE_WITH_UNREACHABLE ? 2 : 1;
    }
    if (out_of_time) return 1;
  }
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
  double mission_s = 0.0;
  app.add_option("--follow-mission", mission_s,
                 "instead: follow EXPLORE_STATE until the mission is over or has run this many seconds of its "
                 "own clock (exit 0 on DONE, 2 on DONE_WITH_UNREACHABLE, 3 when EXPLORE_STATE stopped, 1 otherwise)")
      ->check(CLI::PositiveNumber);
  double wall_limit_s = 0.0;
  app.add_option("--wall-limit", wall_limit_s,
                 "with --follow-mission: give up after this many wall-clock seconds (default: 3 x the mission "
                 "limit + 120, for a mission clock that stands still)")
      ->check(CLI::PositiveNumber);
  double state_timeout_s = 30.0;
  app.add_option("--state-timeout", state_timeout_s,
                 "with --follow-mission: give up (exit 3) after this many wall-clock seconds without an "
                 "EXPLORE_STATE, from the start or since the last one (the explorer is not running)")
      ->check(CLI::PositiveNumber);
  if (const auto code = pex::cli::parse_command_line(app, "pex-status", argc, argv)) return *code;

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "pex-status: cannot open LCM at '%s'\n", url.c_str());
    return EX_UNAVAILABLE;
  }
  if (mission_s > 0)
    return follow_mission(lcm, mission_s, 5.0, wall_limit_s > 0 ? wall_limit_s : 3 * mission_s + 120,
                          state_timeout_s);
  std::map<std::string, pex::daemon_status_t> latest;
  lcm.subscribeFunction(std::string(pex::runtime::channels::kDaemonStatus), &on_status, &latest);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(50);

  std::printf("%-16s %-9s %7s %9s %9s %8s %7s  %s\n", "daemon", "state", "pid", "in", "out",
              "rejected", "errors", "last error");
  for (const auto& [name, s] : latest) {
    std::printf("%-16s %-9s %7d %9lld %9lld %8lld %7lld  %s\n", name.c_str(), pex::runtime::daemon_state_name(s.state),
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
