#pragma once
// The last N latencies in a fixed ring, summarised (median, p99) on demand. Recording never
// allocates, so the realtime thread may call add(); summaries are computed by whoever reports.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace cvo::daemon {

struct LatencySummary {
  double median_ms = 0, p99_ms = 0;
};

class LatencyWindow {
 public:
  explicit LatencyWindow(std::size_t capacity) : samples_(capacity), scratch_(capacity) {}

  void add(double ms) {
    samples_[next_] = ms;
    next_ = (next_ + 1) % samples_.size();
    count_ = std::min(count_ + 1, samples_.size());
  }

  /// Nearest-rank percentiles of the samples held; all zero when there are none.
  LatencySummary summary() {
    LatencySummary s;
    if (count_ == 0) return s;
    std::copy_n(samples_.begin(), count_, scratch_.begin());
    const auto rank = [&](double q) {
      const auto k = std::min(count_ - 1, static_cast<std::size_t>(q * static_cast<double>(count_)));
      std::nth_element(scratch_.begin(), scratch_.begin() + static_cast<std::ptrdiff_t>(k),
                       scratch_.begin() + static_cast<std::ptrdiff_t>(count_));
      return scratch_[k];
    };
    s.median_ms = rank(0.5);
    s.p99_ms = rank(0.99);
    return s;
  }

 private:
  std::vector<double> samples_, scratch_;
  std::size_t next_ = 0, count_ = 0;
};

}  // namespace cvo::daemon
