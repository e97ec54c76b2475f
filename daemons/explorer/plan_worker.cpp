#include "plan_worker.hpp"

#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <stdexcept>

namespace pex::explorer {

double thread_cpu_ms() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

PlanWorker::PlanWorker() {
  event_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (event_fd_ < 0) throw std::runtime_error("plan worker: eventfd failed");
  thread_ = std::thread([this] { run(); });
}

PlanWorker::~PlanWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  ::close(event_fd_);
}

void PlanWorker::submit(planning::PlanRequest request) {
  {
    std::lock_guard lock(mutex_);
    next_ = std::move(request);
  }
  wake_.notify_all();
}

std::optional<TimedPlanResult> PlanWorker::take_result() {
  std::uint64_t count = 0;
  [[maybe_unused]] const auto n = ::read(event_fd_, &count, sizeof count);  // EAGAIN when none: fine
  std::lock_guard lock(mutex_);
  std::optional<TimedPlanResult> out = std::move(done_);
  done_.reset();
  return out;
}

void PlanWorker::run() {
  for (;;) {
    planning::PlanRequest request;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || next_.has_value(); });
      if (stop_) return;
      request = std::move(*next_);
      next_.reset();
    }
    const auto started = std::chrono::steady_clock::now();
    const double cpu_started = thread_cpu_ms();
    TimedPlanResult timed;
    timed.kind = planning::plan_kind(request);
    try {
      timed.result = planning::compute_plan(request, &cache_);
    } catch (const std::exception& e) {
      // The planner's geometry failing is a failed plan, not a dead daemon.
      timed.result = planning::PlanResult{request.id, planning::Plan{}};
      timed.result.plan.error = std::string("planner threw: ") + e.what();
    }
    timed.compute_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
    timed.compute_cpu_ms = thread_cpu_ms() - cpu_started;
    timed.offset_tiles = cache_.offsets.counters();
    timed.graph_tests = cache_.visibility_counters();
    {
      std::lock_guard lock(mutex_);
      done_ = std::move(timed);
    }
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(event_fd_, &one, sizeof one);
  }
}

}  // namespace pex::explorer
