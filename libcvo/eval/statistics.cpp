#include "libcvo/eval/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace cvo::eval {

ErrorStatistics summarize(std::span<const double> errors) {
  if (errors.empty()) throw std::invalid_argument("cannot summarise an empty list of errors");
  const auto n = static_cast<double>(errors.size());
  ErrorStatistics s;
  s.count = errors.size();
  double sum = 0, sum_sq = 0;
  for (const double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.rmse = std::sqrt(sum_sq / n);
  s.mean = sum / n;
  // Deviation from the mean in a second pass: sum_sq / n - mean^2 cancels badly for small spreads.
  double dev_sq = 0;
  for (const double e : errors) dev_sq += (e - s.mean) * (e - s.mean);
  s.stddev = std::sqrt(dev_sq / n);

  std::vector<double> sorted(errors.begin(), errors.end());
  std::sort(sorted.begin(), sorted.end());
  const std::size_t mid = sorted.size() / 2;
  s.median = (sorted.size() % 2 == 1) ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  s.min = sorted.front();
  s.max = sorted.back();
  return s;
}

}  // namespace cvo::eval
