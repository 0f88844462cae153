#pragma once
// The p-th percentile of a list of values, numpy's default (np.percentile, method "linear"). With
// the n values sorted, v_0 <= ... <= v_{n-1}, the rank r = p/100 (n - 1) falls between v_i and
// v_{i+1}, i = floor(r), t = r - i:
//   percentile = v_i + t (v_{i+1} - v_i)             for t < 1/2
//              = v_{i+1} - (1 - t) (v_{i+1} - v_i)   for t >= 1/2 (numpy's form: exact at either end)
// so p = 0 is the minimum, p = 100 the maximum and p = 50 the median (the two middle values' mean
// for an even n). One definition for every report: cvo-run's time per frame, the benchmarks'
// tables and the daemons' CVO_STATUS latency. Header only, so that a daemon uses it without
// linking cvo::eval (whose figures bring OpenCV's image codecs).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <stdexcept>
#include <vector>

namespace cvo::eval {

/// The percentile (p in [0, 100]) of `values`, which it reorders: no allocation and O(n) (two
/// selections, no sort), so a realtime process may summarise a buffer it owns. NaN for no values;
/// std::invalid_argument for a p outside [0, 100].
inline double percentile_in_place(std::span<double> values, double p) {
  if (!(p >= 0 && p <= 100)) throw std::invalid_argument("percentile: p must be in [0, 100]");
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double rank = p / 100 * static_cast<double>(values.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(rank));
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(i);
  std::nth_element(values.begin(), at, values.end());
  const double below = *at;
  if (i + 1 == values.size()) return below;
  const double above = *std::min_element(at + 1, values.end());  // v_{i+1}: the least of those after v_i
  const double t = rank - static_cast<double>(i);
  return t < 0.5 ? below + t * (above - below) : above - (1 - t) * (above - below);
}

/// The same, `values` left as they are (the selection runs on a copy).
inline double percentile(std::span<const double> values, double p) {
  std::vector<double> copy(values.begin(), values.end());
  return percentile_in_place(copy, p);
}

}  // namespace cvo::eval
