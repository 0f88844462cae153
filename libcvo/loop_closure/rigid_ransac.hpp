#pragma once
// The rigid transform between two sets of 3-D points with putative correspondences src[k] <-> dst[k],
// some of them wrong (paper section 5: the initial loop pose from matched ORB features and depth).
//
// Fit: the least-squares rigid transform of a set S of correspondences,
//   T* = argmin_{R, t} Σ_{k in S} |dst_k - (R src_k + t)|²,
// in closed form by the SVD of the cross-covariance (Umeyama 1991 without scale; Eigen::umeyama).
//
// RANSAC: `ransac_iterations` minimal sets of 3 correspondences, drawn from a std::mt19937 seeded
// with `ransac_seed` (so the result is a pure function of the input); a set is skipped when its
// triangle is degenerate in either cloud or its pairwise distances disagree by more than 2 inlier
// thresholds (a rigid motion preserves them, so such a set holds an outlier). Each fit counts the inliers,
// |dst_k - T src_k| < ransac_inlier_m; the first fit with the most inliers wins. The winner is
// refitted on its inliers, the inliers are recounted with the refit, and refitted once more:
// a least-squares estimate from all the inliers, not from 3 noisy points.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/se3.hpp"

namespace cvo::loop_closure {

struct RigidFit {
  bool found = false;
  core::SE3 transform;               // dst ≈ T src
  std::vector<std::size_t> inliers;  // indices k of the correspondences within the threshold, ascending
  double rms_m = 0;                  // RMS residual over the inliers
};

/// The Umeyama fit on the correspondences listed in `subset` (all when it is empty); nullopt when
/// there are fewer than 3 or the result is not finite. src and dst must have the same size.
std::optional<core::SE3> fit_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                                   const std::vector<std::size_t>& subset = {});

/// RANSAC + refit as above, with the ransac_* and min_inliers members of `parameters` (the rest is
/// the loop verification's). found is false when src and dst differ in size, there are fewer than
/// 3 correspondences, or no model reaches max(3, min_inliers) inliers.
RigidFit ransac_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                      const core::LoopVerificationParameters& parameters);

}  // namespace cvo::loop_closure
