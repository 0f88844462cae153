#pragma once
// core::SE3 and 6x6 matrices <-> the fields of cvo_lcm messages, and microsecond timestamps.
//
// pose3d_t holds position[3] and orientation[4] as a unit quaternion in the order w, x, y, z.
// 6x6 matrices (covariance, information) are double[36], row-major.
#include <cstdint>
#include <optional>
#include <string>

#include "cvo_lcm/pose3d_t.hpp"
#include "libcvo/core/se3.hpp"

namespace cvo::lcm {

cvo_lcm::pose3d_t to_message(const core::SE3& pose);

/// nullopt (and why, in *error) when a value is not finite or the quaternion's norm is not 1
/// within 1e-6 (a sender that normalises, as SE3 does, is far closer); the quaternion is then
/// normalised, so a pose survives a round trip exactly.
std::optional<core::SE3> from_message(const cvo_lcm::pose3d_t& message, std::string* error);
/// Every number of the pose is finite (a refusal of kind ContentFailure::kNotFinite when not).
bool is_finite(const cvo_lcm::pose3d_t& message);

void matrix6_to_message(const core::Matrix6d& matrix, double (&out)[36]);
core::Matrix6d matrix6_from_message(const double (&in)[36]);

/// Seconds (as RgbdFrame and trajectories hold them) <-> LCM's utime, rounded to the microsecond.
/// A TUM timestamp (6 decimals) survives the round trip exactly.
std::int64_t to_utime(double seconds);
double from_utime(std::int64_t utime);

}  // namespace cvo::lcm
