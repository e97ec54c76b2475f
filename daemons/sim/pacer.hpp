#pragma once
// Holds the simulated clock back while the robot's software lags behind it.
//
// Every daemon runs on SIM_CLOCK, but their work takes wall time: at 10x
// speed a 40 ms SLAM update is 0.4 s of simulated time in which no pose comes
// out, and on a loaded machine a daemon descheduled for 50 ms misses half a
// second of simulated heartbeats. A real robot's software never falls that far
// behind the world, so a fast simulation must not let it either: the pacer
// watches the newest stamp (simulated utime) of a few channels the set
// publishes as it keeps up (SLAM_POSE: the end of the sensing chain;
// BASE_CMD: the end of the control chain; MAP: the mapper, whose inserts are
// the slowest work) and the simulator advances only while none of them is
// more than max_lag_us (plus its own period) behind. Then a run's outcome does
// not depend on the speed factor or the machine's load, only its wall time.
//
// A channel that has gone silent (a daemon died or never started) stops
// holding the clock after silence_wall_s of wall time, so faults can still be
// simulated; it holds again once it is heard again. Pure: times come in.
//
// The simulator holds its clock by the same rule at each simulated drive's
// heartbeat watchdog (Simulator::drive_watchdog_waits): a master heard within
// silence_wall_s of wall time is late, not dead, and the watchdog waits for it.
#include <cstdint>
#include <string>
#include <vector>

namespace pex::simd {

struct PacingOptions {
  std::vector<std::string> channels = {"SLAM_POSE", "BASE_CMD"};
  // Each channel's publication period (us, parallel to channels; missing or 0:
  // none): a channel published every period_us is that much behind at worst
  // while keeping up, so it may lag max_lag_us + its period.
  std::vector<std::int64_t> periods_us;
  std::int64_t max_lag_us = 150'000;  // simulated time a channel may lag (0: pacing off)
  double silence_wall_s = 2.0;        // wall time after which a silent channel no longer holds
};

class Pacer {
 public:
  explicit Pacer(PacingOptions options);

  const PacingOptions& options() const { return options_; }
  // A message on channels()[index] stamped `stamp_us` (simulated utime) arrived at `wall_s`.
  void on_stamp(std::size_t index, std::int64_t stamp_us, double wall_s);
  // May the clock advance past `sim_utime_us` now? False while a channel heard
  // within silence_wall_s lags by more than max_lag_us.
  bool may_advance(std::int64_t sim_utime_us, double wall_s) const;
  // The channel holding the clock ("" if none), for the sim's health.
  std::string holding(std::int64_t sim_utime_us, double wall_s) const;

 private:
  struct Channel {
    bool heard = false;
    std::int64_t stamp_us = 0;
    double wall_s = 0.0;
  };
  PacingOptions options_;
  std::vector<Channel> channels_;
};

}  // namespace pex::simd
