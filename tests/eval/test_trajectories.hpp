#pragma once
// Hand-built trajectories for the evaluation tests. Timestamps are multiples of 1/8 s so that
// t + delta lands exactly on a stamp and every expected number can be worked out by hand.
#include <cmath>
#include <cstddef>
#include <functional>

#include "libcvo/core/trajectory.hpp"

namespace cvo::eval::testing {

constexpr double kStep = 0.125;  // s

inline core::SE3 rot_z(double radians) { return core::SE3::from_rotation_vector({0, 0, radians}); }

/// n poses at t = t0 + k * kStep, pose(t) given.
inline core::Trajectory make(std::size_t n, const std::function<core::SE3(double)>& pose, double t0 = 0.0) {
  core::Trajectory t;
  for (std::size_t k = 0; k < n; ++k) {
    const double stamp = t0 + kStep * static_cast<double>(k);
    t.push_back({stamp, pose(stamp)});
  }
  return t;
}

/// A helix that turns while it moves: not planar, not degenerate for alignment.
inline core::SE3 helix(double t) {
  const Eigen::Vector3d p(std::cos(t), 1.5 * std::sin(0.7 * t), 0.2 * t);
  return {core::so3_exp({0.1 * t, -0.05 * t, 0.3 * t}), p};
}

/// Left-multiplies every pose: the same motion seen from another world frame.
inline core::Trajectory transformed(const core::SE3& world_change, core::Trajectory t) {
  for (auto& p : t) p.pose = world_change * p.pose;
  return t;
}

}  // namespace cvo::eval::testing
