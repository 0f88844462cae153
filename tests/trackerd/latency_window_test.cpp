// LatencyWindow: CVO_STATUS's median and p99 are eval::percentile's (numpy's) over the last N
// latencies, and summarising them allocates nothing.
#include <gtest/gtest.h>

#include "daemon/common/latency_window.hpp"
#include "program/allocation_counter.hpp"

namespace cvo::daemon {
namespace {

TEST(LatencyWindow, SummarisesTheLastSamplesWithNumpysPercentile) {
  LatencyWindow window(4);
  EXPECT_EQ(window.summary().median_ms, 0) << "no sample yet";
  for (const double ms : {100.0, 4.0, 1.0, 3.0, 2.0}) window.add(ms);  // 100 falls out of the window
  const auto s = window.summary();
  EXPECT_DOUBLE_EQ(s.median_ms, 2.5);  // np.percentile([4, 1, 3, 2], 50)
  EXPECT_DOUBLE_EQ(s.p99_ms, 3.97);    // np.percentile([4, 1, 3, 2], 99)
}

TEST(LatencyWindow, SummaryAllocatesNothing) {
  LatencyWindow window(64);
  for (int i = 0; i < 100; ++i) window.add(i % 7);
  const auto before = program::thread_allocations();
  const auto s = window.summary();
  EXPECT_EQ(program::thread_allocations() - before, 0);
  EXPECT_GT(s.p99_ms, 0);
}

}  // namespace
}  // namespace cvo::daemon
