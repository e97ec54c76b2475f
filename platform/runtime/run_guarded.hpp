#pragma once
// For tests that run a Node until a state is reached (they call
// request_stop() from a handler): node.run() with a guard against hanging.
// The guard is no time limit under test (a test waits for a state, never a
// duration); it only ends a run whose state never comes, on the monotonic
// clock, so that the test fails on its assertions instead of hanging ctest.
#include <sys/timerfd.h>
#include <unistd.h>

#include "runtime/node.hpp"

namespace pex::runtime {

inline void run_guarded(Node& node, int guard_s = 60) {
  const int guard = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
  itimerspec after{};
  after.it_value.tv_sec = guard_s;
  timerfd_settime(guard, 0, &after, nullptr);
  node.watch_fd(guard, [&] { node.request_stop(); });
  node.run();
  close(guard);
}

}  // namespace pex::runtime
