#pragma once
// The a posteriori variance factor of the registrations, from the tracker's own redundancy.
//
// Each fused frame n is measured twice relative to its keyframe m: by the keyframe edge T_m^n and
// by the chain C = T̄_m^{n-1} T_{n-1}^n. With covariances that are right, their disagreement
// d = log(C T_m^n⁻¹) is N(0, S), S = Σ_kf + Σ̄_{n-1} + Ad Σ_f Adᵀ (pose_covariance.hpp), so
// χ² = dᵀ S⁻¹ d averages 6. The ratio of the χ² seen to 6 is the classical variance factor of unit
// weight σ̂₀² = vᵀPv / r of an adjustment with redundancy r (Gauss; Koch, "Parameter Estimation and
// Hypothesis Testing in Linear Models"): what the sandwich (registration/edge_covariance.hpp) misses, because
// the points' terms are more alike than it assumes, scales every registration's covariance alike,
// and this measures it on the running sequence, with no ground truth and no constant fitted to any
// sequence. The estimate is the mean over the session's fused frames with a prior of
// kPriorFrames frames at 1 (the sandwich taken at its word until the data say otherwise); each
// χ² is capped at kMaxChi2Ratio times the current factor's expectation, so a frame whose two
// registrations disagree grossly (a failed one) cannot move it far.
//
// Its blind spot: an error of frame n's cloud that moves both of its registrations alike (a
// colour-depth time offset, a rolling shutter's skew) cancels in d. Such errors are not in the
// factor; bench/odometry-tuning.md, "Covariance", measures what that leaves on real sequences.
#include "libcvo/core/se3.hpp"

namespace cvo::odometry {

struct VarianceFactor {
  double chi2_sum = 0;  // Σ χ² / 6 (capped) over the fused frames
  double frames = 0;

  /// σ̂₀²: multiplies every registration covariance.
  [[nodiscard]] double value() const;
};

/// dᵀ S⁻¹ d; nullopt-like -1 when S is not positive definite.
double disagreement_chi2(const core::Vector6d& d, const core::Matrix6d& S);

/// Adds one fused frame's χ² (ignored when negative or not finite).
void add_disagreement(VarianceFactor& factor, double chi2);

}  // namespace cvo::odometry
