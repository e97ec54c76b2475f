// pex-explorer: will choose frontier goals, plan on the offset map and follow paths.
// Until that work lands it only reports its health and an EXPLORE_STATE that says,
// in its status text, that exploration is not implemented — so nobody mistakes it
// for a running mission.
#include <chrono>

#include <pex/explore_state_t.hpp>
#include <spdlog/spdlog.h>

#include "runtime/channels.hpp"
#include "runtime/daemon.hpp"

namespace {

struct ExplorerOptions {
  double state_rate_hz = 2.0;  // EXPLORE_STATE publication rate
};

ExplorerOptions load_options(pex::runtime::ConfigReader& config) {
  ExplorerOptions o;
  o.state_rate_hz =
      config.get<double>("state_rate_hz", o.state_rate_hz, pex::runtime::in_range(0.1, 100.0));
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  return pex::runtime::run_daemon(
      argc, argv, {"explorer", "frontier exploration (not implemented yet: reports idle)"},
      [](pex::runtime::Node& node, pex::runtime::ConfigReader& config) {
        const ExplorerOptions options = load_options(config);
        spdlog::warn("exploration is not implemented yet: publishing EXPLORE_STATE idle only");
        node.every(std::chrono::microseconds(static_cast<int64_t>(1e6 / options.state_rate_hz)),
                   [&node](int64_t now_utime) {
                     pex::explore_state_t s{};
                     s.utime = now_utime;
                     s.phase = pex::explore_state_t::PHASE_IDLE;
                     s.status = "exploration not implemented yet";
                     node.publish(pex::runtime::channels::kExploreState, s);
                   });
      });
}
