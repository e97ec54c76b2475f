// pex-mission: commands the exploration mission on MISSION_CMD —
//   pex-mission start | pause | resume | home | stop
// and waits until EXPLORE_STATE shows the command took effect. The command
// is sent again every half second until then (the explorer applies it
// idempotently), so a lost datagram or an explorer that starts late does not
// lose it. Exit 0 once applied, 1 when not applied within --timeout.
#include <chrono>
#include <cstdio>
#include <map>
#include <string>

#include <CLI/CLI.hpp>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <lcm/lcm-cpp.hpp>
#include <pex/explore_state_t.hpp>
#include <pex/mission_cmd_t.hpp>

#include "cli/command_line.hpp"
#include "planning/mission.hpp"
#include "runtime/channels.hpp"

namespace {

using pex::planning::Phase;

// Does the phase show the command in effect?
bool applied(pex::planning::MissionCommand command, Phase phase) {
  using pex::planning::MissionCommand;
  switch (command) {
    case MissionCommand::kStart:
    case MissionCommand::kResume:
      return phase == Phase::kIdle || phase == Phase::kSelecting || phase == Phase::kMoving;
    case MissionCommand::kPause: return phase == Phase::kPaused;
    case MissionCommand::kHome: return phase == Phase::kHoming || phase == Phase::kHome;
    case MissionCommand::kStop: return phase == Phase::kStopped;
  }
  return false;
}

// Subscribed through a plain function (subscribeFunction), not a member
// function pointer: GCC's UBSan misreads LCM 1.3's member-pointer dispatch
// (lcm-cpp-impl.hpp) as a member access at address 0x1, which fails the
// sanitizer build (scripts/test.sh --sanitize).
struct StateListener {
  static void on_state(const lcm::ReceiveBuffer*, const std::string&, const pex::explore_state_t* s,
                       StateListener* self) {
    self->state = *s;
    self->heard = true;
  }
  pex::explore_state_t state{};
  bool heard = false;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Command the exploration mission (MISSION_CMD) and wait until EXPLORE_STATE shows it",
               "pex-mission"};
  std::string url;
  std::string command_name;
  double timeout_s = 10.0;
  app.add_option("command", command_name, "start, pause, resume, home or stop")
      ->required()
      ->check(CLI::IsMember({"start", "pause", "resume", "home", "stop"}));
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL or LCM's)");
  app.add_option("--timeout", timeout_s, "seconds to wait for the explorer to show the command in effect")
      ->check(CLI::PositiveNumber);
  if (const auto code = pex::cli::parse_command_line(app, "pex-mission", argc, argv)) return *code;

  const std::map<std::string, pex::planning::MissionCommand> commands = {
      {"start", pex::planning::MissionCommand::kStart}, {"pause", pex::planning::MissionCommand::kPause},
      {"resume", pex::planning::MissionCommand::kResume}, {"home", pex::planning::MissionCommand::kHome},
      {"stop", pex::planning::MissionCommand::kStop}};
  const auto command = commands.at(command_name);

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "pex-mission: cannot open LCM at '%s'\n", url.c_str());
    return EX_UNAVAILABLE;
  }
  StateListener listener;
  lcm.subscribeFunction(std::string(pex::runtime::channels::kExploreState), &StateListener::on_state, &listener);
  const pex::explore_state_t& state = listener.state;
  const bool& heard = listener.heard;

  pex::mission_cmd_t msg{};
  msg.command = static_cast<std::int8_t>(command);
  msg.source = "pex-mission";
  const auto start = std::chrono::steady_clock::now();
  auto next_send = start;
  while (true) {
    const auto now = std::chrono::steady_clock::now();
    if (heard && applied(command, static_cast<Phase>(state.phase))) {
      std::printf("pex-mission: %s applied: %s: %s\n", command_name.c_str(),
                  pex::planning::to_string(static_cast<Phase>(state.phase)), state.status.c_str());
      return 0;
    }
    if (now - start > std::chrono::duration<double>(timeout_s)) {
      if (heard)
        std::fprintf(stderr, "pex-mission: %s not applied within %.1f s; the mission is %s: %s\n",
                     command_name.c_str(), timeout_s, pex::planning::to_string(static_cast<Phase>(state.phase)),
                     state.status.c_str());
      else
        std::fprintf(stderr, "pex-mission: no EXPLORE_STATE heard within %.1f s: is pex-explorer running?\n",
                     timeout_s);
      return 1;
    }
    if (now >= next_send) {
      msg.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                      std::chrono::system_clock::now().time_since_epoch())
                      .count();
      lcm.publish(std::string(pex::runtime::channels::kMissionCmd), &msg);
      next_send = now + std::chrono::milliseconds(500);
    }
    lcm.handleTimeout(50);
  }
}
