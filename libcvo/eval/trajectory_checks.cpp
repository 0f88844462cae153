#include "libcvo/eval/trajectory_checks.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace cvo::eval {

core::Trajectory sorted_unique(const core::Trajectory& trajectory, std::string_view what) {
  core::Trajectory sorted = trajectory;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.timestamp < b.timestamp; });
  const auto dup = std::adjacent_find(sorted.begin(), sorted.end(),
                                      [](const auto& a, const auto& b) { return a.timestamp == b.timestamp; });
  if (dup != sorted.end()) {
    char stamp[64];
    std::snprintf(stamp, sizeof stamp, "%.6f", dup->timestamp);
    throw std::invalid_argument(std::string(what) + " has two poses with timestamp " + stamp);
  }
  return sorted;
}

}  // namespace cvo::eval
