#pragma once
// Summary statistics of a list of errors, computed as numpy does in the TUM benchmark scripts:
//   rmse   = sqrt(sum e_i^2 / n)
//   mean   = sum e_i / n
//   median = middle value of the sorted list; the mean of the two middle values when n is even
//   stddev = sqrt(sum (e_i - mean)^2 / n)   (population deviation: numpy's default ddof = 0)
//   min, max.
#include <cstddef>
#include <span>

namespace cvo::eval {

struct ErrorStatistics {
  double rmse = 0;
  double mean = 0;
  double median = 0;
  double stddev = 0;
  double min = 0;
  double max = 0;
  std::size_t count = 0;
};

/// Throws std::invalid_argument on an empty list: no statistic of nothing is meaningful.
ErrorStatistics summarize(std::span<const double> errors);

}  // namespace cvo::eval
