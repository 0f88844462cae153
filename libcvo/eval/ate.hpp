#pragma once
// Absolute trajectory error (ATE), exactly as the TUM RGB-D benchmark's evaluate_ate.py:
//   1. associate estimate to ground-truth timestamps as associate.py does: every pair with
//      |t_gt - (t_est + offset)| < max_difference (strict) is a candidate, candidates are taken
//      greedily by increasing difference, each pose at most once (core::associate);
//   2. align the associated estimate positions onto the ground-truth positions with a rigid
//      transform WITHOUT scale (Horn / Umeyama, see alignment.hpp);
//   3. the error of pair i is |S p_est,i - p_gt,i|, S the alignment; only positions count.
// The script accepts 2 pairs; 3 is asked here, the fewest that fix a rigid alignment of a curve.
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/se3.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/eval/statistics.hpp"

namespace cvo::eval {

struct AteOptions {
  double max_difference = 0.02;  // s, association window (strict <): associate.py's default
  double offset = 0.0;           // s, added to the estimate's timestamps before associating
};

struct AtePair {
  double gt_timestamp = 0;
  double est_timestamp = 0;
  Eigen::Vector3d gt_position = Eigen::Vector3d::Zero();
  Eigen::Vector3d aligned_position = Eigen::Vector3d::Zero();  // alignment * estimate position
  double error = 0;                                            // m, |aligned - gt|
};

struct AteResult {
  core::SE3 alignment;         // maps estimate positions onto the ground truth
  std::vector<AtePair> pairs;  // the associated pairs, by increasing ground-truth timestamp
  ErrorStatistics error;       // m, over pairs (error.count == pairs.size())
};

/// Throws std::invalid_argument when fewer than 3 pairs associate, when an option is not finite
/// or max_difference <= 0, or when a trajectory repeats a timestamp.
AteResult absolute_trajectory_error(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                                    const AteOptions& options = {});

}  // namespace cvo::eval
