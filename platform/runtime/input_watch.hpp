#pragma once
// Which of a daemon's inputs have gone quiet. A daemon that cannot do its job
// for want of an input (no scans, no poses, no updates) must say so in its
// health rather than report OK: the daemon registers each input with its
// timeout, marks it seen on every message, and asks stale() on a timer. Time
// is passed in (the node's monotonic clock), so the logic is tested without a
// bus. An input never seen is counted from the first call with a time.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pex::runtime {

class InputWatch {
 public:
  // `name` as it should read in the health text ("LIDAR_SCAN").
  void expect(std::string name, std::int64_t timeout_us) { inputs_.push_back({std::move(name), timeout_us, -1}); }

  void seen(std::string_view name, std::int64_t now_us) {
    start(now_us);
    for (auto& i : inputs_)
      if (i.name == name) i.last_us = now_us;
  }

  // "" when every input came within its timeout; else why not, naming the
  // first input that did not ("no LIDAR_SCAN for 2.4 s" / "no LIDAR_SCAN yet").
  std::string stale(std::int64_t now_us) {
    start(now_us);
    for (const auto& i : inputs_) {
      const std::int64_t since = i.last_us >= 0 ? i.last_us : start_us_;
      if (now_us - since <= i.timeout_us) continue;
      if (i.last_us < 0) return "no " + i.name + " yet";
      const std::int64_t tenths = (now_us - i.last_us) / 100'000;
      return "no " + i.name + " for " + std::to_string(tenths / 10) + "." + std::to_string(tenths % 10) + " s";
    }
    return {};
  }

 private:
  void start(std::int64_t now_us) {
    if (start_us_ < 0) start_us_ = now_us;
  }
  struct Input {
    std::string name;
    std::int64_t timeout_us;
    std::int64_t last_us;
  };
  std::vector<Input> inputs_;
  std::int64_t start_us_ = -1;
};

}  // namespace pex::runtime
