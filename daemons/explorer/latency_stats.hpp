#pragma once
// Percentiles of a duration measured over a whole mission (plan times,
// control-step times), for DAEMON_STATUS and the exploration benchmark.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace pex::explorer {

class LatencyStats {
 public:
  // Past this many samples every other one is dropped and only every other
  // new one kept: memory stays bounded and the percentiles stay a fair sample.
  explicit LatencyStats(std::size_t max_samples = 1 << 16) : max_samples_(max_samples) {}

  void add(double value) {
    if (++seen_ % stride_ != 0) return;
    samples_.push_back(value);
    if (samples_.size() >= max_samples_) {
      std::size_t kept = 0;
      for (std::size_t i = 0; i < samples_.size(); i += 2) samples_[kept++] = samples_[i];
      samples_.resize(kept);
      stride_ *= 2;
    }
  }
  // The q-quantile (0..1) of the samples, nearest rank; 0 without samples.
  double quantile(double q) const {
    if (samples_.empty()) return 0.0;
    std::vector<double> v = samples_;
    const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1) + 0.5);
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }

 private:
  std::size_t max_samples_;
  std::vector<double> samples_;
  unsigned long long seen_ = 0;
  unsigned long long stride_ = 1;
};

}  // namespace pex::explorer
