#pragma once
// The last N latencies in a fixed ring, summarised (median, p99) on demand. Recording never
// allocates, so the realtime thread may call add(); summaries are computed by whoever reports.
#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

#include "libcvo/eval/percentile.hpp"

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

  /// The percentiles of the samples held (eval::percentile, numpy's, on a copy made in the
  /// scratch buffer: no allocation); all zero when there are none.
  LatencySummary summary() {
    LatencySummary s;
    if (count_ == 0) return s;
    const std::span<double> held(scratch_.data(), count_);
    std::copy_n(samples_.begin(), count_, held.begin());
    s.median_ms = eval::percentile_in_place(held, 50);
    s.p99_ms = eval::percentile_in_place(held, 99);
    return s;
  }

 private:
  std::vector<double> samples_, scratch_;
  std::size_t next_ = 0, count_ = 0;
};

}  // namespace cvo::daemon
