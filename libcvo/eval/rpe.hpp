#pragma once
// Relative pose error (RPE), exactly as the TUM RGB-D benchmark's evaluate_rpe.py run with
// --fixed_delta --delta_unit s (the setting of the benchmark's online tool, delta = 1 s):
//   * both trajectories sorted by timestamp; est_k, gt_k their stamps;
//   * for every estimate index i: j = find_closest_index(est, est_i + delta); the pair (i, j) is
//     kept only when j is not the last index. This drops the pairs that would end on the last
//     pose, a quirk of the script replicated here so that the numbers agree with it;
//   * the ground-truth poses of a pair are those nearest in time, G_i at
//     find_closest_index(gt, est_i + offset) and G_j likewise; the pair is skipped when either lies
//     more than 2 * median(gt_{k+1} - gt_k) from its estimate stamp;
//   * with A = E_i^-1 E_j (estimated motion) and B = G_i^-1 G_j (true motion) the script computes
//     ominus(ominus(E_j, E_i), ominus(G_j, G_i)) = (E_j^-1 E_i)^-1 (G_j^-1 G_i) = A B^-1, and
//        translational error = |translation(A B^-1)|                 (m per delta)
//        rotational error    = arccos(clamp((trace(R(A B^-1)) - 1) / 2, -1, 1))
//     The arccos of a trace resolves angles only down to about 1e-8 rad; that is the script's.
// Errors are not divided by delta: with delta = 1 s they are m/s and deg/s, as published.
// The script draws a random sample of 10000 pairs when there are more (about 5.5 min at 30 Hz);
// all pairs are evaluated here, so on longer sequences the two can differ by sampling noise.
#include <vector>

#include "libcvo/core/se3.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/eval/statistics.hpp"

namespace cvo::eval {

struct RpeOptions {
  double delta = 1.0;   // s, time between the two poses of a pair
  double offset = 0.0;  // s, added to the estimate's timestamps before looking up ground truth
};

struct RpePair {
  double est_timestamp_0 = 0, est_timestamp_1 = 0;  // E_i, E_j
  double gt_timestamp_0 = 0, gt_timestamp_1 = 0;    // G_i, G_j
  double translation = 0;                           // m
  double rotation_deg = 0;                          // degrees
};

struct RpeResult {
  double delta = 1.0;            // s, as evaluated
  std::vector<RpePair> pairs;    // by increasing est_timestamp_0
  ErrorStatistics translation;   // m per delta
  ErrorStatistics rotation_deg;  // degrees per delta
};

/// The error transform A B^-1 of one pair (see above).
core::SE3 relative_pose_error_transform(const core::SE3& est_i, const core::SE3& est_j, const core::SE3& gt_i,
                                        const core::SE3& gt_j);

/// arccos(clamp((trace(R) - 1) / 2)): the script's compute_angle, radians in [0, pi].
double rotation_angle_from_trace(const core::SE3& transform);

/// Throws std::invalid_argument when delta is not finite and > 0, when the offset is not finite,
/// when either trajectory has fewer than 2 poses or repeats a timestamp, when fewer than 2
/// estimate stamps overlap the ground truth, or when fewer than 2 pairs remain (all as the script).
RpeResult relative_pose_error(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                              const RpeOptions& options = {});

}  // namespace cvo::eval
