#include "libcvo/core/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace cvo::core {

std::size_t find_closest_index(const std::vector<double>& sorted, double t) {
  // Binary search; the closest element is one of the two around the insertion point.
  const auto it = std::lower_bound(sorted.begin(), sorted.end(), t);
  if (it == sorted.begin()) return 0;
  if (it == sorted.end()) return sorted.size() - 1;
  const auto hi = static_cast<std::size_t>(it - sorted.begin());
  return (std::abs(sorted[hi] - t) < std::abs(sorted[hi - 1] - t)) ? hi : hi - 1;
}

std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& a, const std::vector<double>& b,
                                                           double max_difference, double offset) {
  // Candidates only within the window; both lists need not be sorted, so sort b's indices once.
  std::vector<std::size_t> b_order(b.size());
  for (std::size_t j = 0; j < b.size(); ++j) b_order[j] = j;
  std::sort(b_order.begin(), b_order.end(), [&](std::size_t x, std::size_t y) { return b[x] < b[y]; });
  std::vector<double> b_sorted(b.size());
  for (std::size_t k = 0; k < b.size(); ++k) b_sorted[k] = b[b_order[k]] + offset;

  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < a.size(); ++i) {
    auto lo = std::lower_bound(b_sorted.begin(), b_sorted.end(), a[i] - max_difference);
    for (auto it = lo; it != b_sorted.end() && *it < a[i] + max_difference; ++it) {
      const double d = std::abs(a[i] - *it);
      if (d < max_difference) candidates.emplace_back(d, i, b_order[static_cast<std::size_t>(it - b_sorted.begin())]);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const auto& [d, i, j] : candidates) {
    if (used_a[i] || used_b[j]) continue;
    used_a[i] = used_b[j] = true;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

std::vector<double> timestamps(const Trajectory& trajectory) {
  std::vector<double> t;
  t.reserve(trajectory.size());
  for (const auto& p : trajectory) t.push_back(p.timestamp);
  return t;
}

}  // namespace cvo::core
