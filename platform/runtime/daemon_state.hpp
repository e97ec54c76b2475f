#pragma once
// The words for DAEMON_STATUS's state (pex.daemon_status_t STATE_*), one place for the
// journal ("state DEGRADED: ..."), systemd's STATUS= line, pex-status and pex-viewer.

#include <cstdint>
#include <string>

namespace pex::runtime {

// A daemon core's health as its daemon publishes it: the state
// (daemon_status_t::STATE_*) and why, when it is not OK.
struct DaemonHealth {
  std::int8_t state = 0;
  std::string reason;
};

constexpr const char* daemon_state_name(int state) {
  constexpr const char* kNames[] = {"STARTING", "OK", "DEGRADED", "ERROR", "STOPPING"};  // STATE_STARTING = 0 ...
  return state >= 0 && state < static_cast<int>(sizeof kNames / sizeof kNames[0]) ? kNames[state] : "UNKNOWN";
}

}  // namespace pex::runtime
