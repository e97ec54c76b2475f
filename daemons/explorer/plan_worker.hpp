#pragma once
// Runs the mission's plans on a thread of their own, so the explorer's 10 Hz
// control step never waits for a plan (planning takes from a millisecond to
// tens of milliseconds on a big map). One request at a time: a newer request
// replaces one that has not started yet. When a result is ready the worker
// makes fd() readable, so the daemon's poll loop picks it up at once.
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

#include "planning/mission.hpp"

namespace pex::explorer {

struct TimedPlanResult {
  planning::PlanResult result;
  planning::PlanKind kind = planning::PlanKind::kSelect;  // the request's (planning::plan_kind)
  double compute_ms = 0.0;      // wall time of compute_plan (steady clock): the plan's latency
  double compute_cpu_ms = 0.0;  // CPU time of the thread that ran it: the planner's own cost,
                                // which a loaded machine does not inflate
  planning::OffsetTileCache::Counters offset_tiles;  // the worker's cache so far, this plan included
  planning::VisibilityCache::Counters graph_tests;   // likewise
};

// CPU time consumed by the calling thread so far, in ms.
double thread_cpu_ms();

class PlanWorker {
 public:
  PlanWorker();
  ~PlanWorker();  // stops and joins the thread
  PlanWorker(const PlanWorker&) = delete;
  PlanWorker& operator=(const PlanWorker&) = delete;

  void submit(planning::PlanRequest request);
  // The newest finished result, if any (clears fd()'s readiness).
  std::optional<TimedPlanResult> take_result();
  // An eventfd, readable while a result waits.
  int fd() const { return event_fd_; }

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<planning::PlanRequest> next_;
  std::optional<TimedPlanResult> done_;
  bool stop_ = false;
  int event_fd_ = -1;
  planning::PlanCache cache_;  // the worker thread's alone
  std::thread thread_;
};

}  // namespace pex::explorer
