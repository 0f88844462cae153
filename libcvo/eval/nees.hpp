#pragma once
// NEES (normalised estimation error squared) of frame-to-frame relative poses: how well a
// published covariance describes the error it claims.
//
// For each covariance at an estimate stamp t_n (E_n), with E_{n-1} the estimate's pose before it:
//   Â = E_{n-1}⁻¹ E_n,  B = G(t_{n-1})⁻¹ G(t_n),  ξ = log(Â⁻¹ B),  NEES = ξᵀ Σ⁻¹ ξ
// (Σ a right perturbation, B = Â exp(ξ), [rho; phi] as core::SE3). G(t) is the ground truth at t,
// interpolated geodesically between the two poses around t (core::interpolate), each within
// max_difference of t (TUM's association window, 0.02 s): at 30 Hz the nearest ground-truth pose can
// be 5 ms off, which on a fast turn is more rotation than the estimate's error. Pairs without
// ground truth around both stamps, or with a singular Σ, are left out.
// For a consistent estimator with Gaussian errors NEES ~ χ²(6): its mean is 6 (3 for each of the
// translation and rotation parts, with their marginal Σ blocks); over-confidence shows as ≫ 6.
#include <optional>
#include <vector>

#include "libcvo/core/trajectory.hpp"
#include "libcvo/eval/statistics.hpp"
#include "libcvo/io/covariance_io.hpp"

namespace cvo::eval {

struct NeesOptions {
  double max_difference = 0.02;  // s: the ground truth used lies within this of the stamp
};

struct NeesPair {
  double timestamp = 0;  // t_n
  double nees = 0, translation = 0, rotation = 0;
};

struct NeesResult {
  std::vector<NeesPair> pairs;
  ErrorStatistics nees, translation, rotation;  // of the pairs' values (mean, median, ...)
};

/// ξᵀ Σ⁻¹ ξ; the translation / rotation parts with the marginal 3x3 blocks. nullopt: Σ singular.
struct NeesValue {
  double nees = 0, translation = 0, rotation = 0;
};
std::optional<NeesValue> nees(const core::Vector6d& error, const core::Matrix6d& covariance);

/// Throws std::invalid_argument when no pair remains.
NeesResult relative_pose_nees(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                              const std::vector<io::StampedCovariance>& covariances, const NeesOptions& options = {});

}  // namespace cvo::eval
