#pragma once
// Timestamped poses, and the nearest-timestamp association of the TUM benchmark tools.
#include <cstddef>
#include <utility>
#include <vector>

#include "libcvo/core/se3.hpp"

namespace cvo::core {

struct StampedPose {
  double timestamp = 0;  // seconds
  SE3 pose;              // T_world_camera
};

using Trajectory = std::vector<StampedPose>;

/// Index of the element of the sorted list closest to t, as TUM's find_closest_index.
/// `sorted` must not be empty.
std::size_t find_closest_index(const std::vector<double>& sorted, double t);

/// TUM associate.py: every pair (i, j) with |a[i] - (b[j] + offset)| < max_difference is a
/// candidate; candidates are taken greedily by increasing difference, each index used at most
/// once. Returns index pairs sorted by a's index.
std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<double>& a, const std::vector<double>& b,
                                                           double max_difference, double offset = 0.0);

std::vector<double> timestamps(const Trajectory& trajectory);

}  // namespace cvo::core
