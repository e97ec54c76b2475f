#pragma once
// The words for DAEMON_STATUS's state (pex.daemon_status_t STATE_*), one place for the
// journal ("state DEGRADED: ..."), systemd's STATUS= line, pex-status and pex-viewer.

namespace pex::runtime {

constexpr const char* daemon_state_name(int state) {
  constexpr const char* kNames[] = {"STARTING", "OK", "DEGRADED", "ERROR", "STOPPING"};  // STATE_STARTING = 0 ...
  return state >= 0 && state < static_cast<int>(sizeof kNames / sizeof kNames[0]) ? kNames[state] : "UNKNOWN";
}

}  // namespace pex::runtime
