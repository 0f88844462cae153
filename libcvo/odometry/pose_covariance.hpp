#pragma once
// How the covariance of the published poses follows from the registrations' (registration/edge_covariance.hpp),
// by first-order propagation through exactly what KF-CVO computes (keyframe_odometry.hpp).
//
// Conventions. A registration's covariance is a LEFT perturbation in its fixed frame (T_m^n =
// exp(e) T̂_m^n, e in keyframe m's coordinates). The published quantities are RIGHT perturbations
// in [rho; phi] as core::SE3's tangent: P_n = P̂_n exp(ξ) (the odometry pose) and
// T_{n-1}^n = T̂_{n-1}^n exp(ξ) (the relative pose an EKF fuses as visual odometry). A left
// perturbation e of T turns into the right one Ad(T⁻¹) e.
//
// The fusion (KeyframeOdometry's fuse_with_chain): T̄_m^n = exp(K_c d) T_m^n with the gain
// K_c = (H_kf + H_c)⁻¹ H_c of the information it used, d the chain's offset. To first order its
// error is ē_n = (I − K_c) e_kf + K_c e_C, with the chain C = T̄_m^{n-1} T_{n-1}^n erring by
// e_C = ē_{n-1} + Ad(T̄_m^{n-1}) e_f (e_f the frame-to-frame registration's). The registrations'
// errors are taken independent (each is dominated by its moving frame's noise):
//   Σ̄_n = K_kf (Σ_kf) K_kfᵀ + K_c (Σ̄_{n-1} + Ad Σ_f Adᵀ) K_cᵀ,            K_kf = I − K_c.
// The gain is the fusion's own, so a fusion with other weights keeps its covariance honest as
// long as it reports the information it used.
//
// The relative pose T_{n-1}^n = (T̄_m^{n-1})⁻¹ T̄_m^n errs, on the right, by Ad(T̄_m^n⁻¹)(ē_n − ē_{n-1}):
//   Σ_rel = Ad(T̄_m^n)⁻¹ [K_kf (Σ_kf + Σ̄_{n-1}) K_kfᵀ + K_c Ad Σ_f Adᵀ K_cᵀ] Ad(T̄_m^n)⁻ᵀ;
// when frame n-1 is the keyframe it is Σ_f's, on the right: Ad(T_f)⁻¹ Σ_f Ad(T_f)⁻ᵀ.
//
// The odometry pose P_n = P_m T̄_m^n, with P_m's error independent of the edges since m:
//   Σ_O(n) = Ad(T̄_m^n)⁻¹ (Σ_O(m) + Σ̄_n) Ad(T̄_m^n)⁻ᵀ,      Σ_O = 0 at the session's first frame.
// A predicted frame (a failure) measures nothing: its Σ_O is carried unchanged and it has no
// relative covariance.
//
// The map pose M_n = M_k T_k^n, keyframe k placed in the map with the back end's Σ_M(k) (a
// marginal, posegraph/marginals.hpp), composed with the odometry since k. For a chain of
// independent increments Σ_O(n) = Ad(Δ)⁻¹ Σ_O(k) Ad(Δ)⁻ᵀ + Σ_odom(k→n), Δ = T_k^n, so
//   Σ_map(n) = Ad(Δ)⁻¹ Σ_M(k) Ad(Δ)⁻ᵀ + [Σ_O(n) − Ad(Δ)⁻¹ Σ_O(k) Ad(Δ)⁻ᵀ]₊
// with [·]₊ the nearest positive semi-definite matrix (round-off, or a frame tracked against an
// earlier keyframe than k, must not make it indefinite).
#include <optional>

#include "libcvo/core/se3.hpp"

namespace cvo::odometry {

/// The running state of KF-CVO's covariances, within one session.
struct PoseCovarianceChain {
  core::Matrix6d keyframe_odometry = core::Matrix6d::Zero();  // Σ_O(m)
  core::Matrix6d previous_fused = core::Matrix6d::Zero();     // Σ̄_{n-1} (left, keyframe frame; 0 at m)
  core::Matrix6d previous_odometry = core::Matrix6d::Zero();  // Σ_O(n-1)
};

/// What one frame publishes.
struct PoseCovariances {
  std::optional<core::Matrix6d> relative;            // of T_{n-1}^n, right perturbation
  core::Matrix6d odometry = core::Matrix6d::Zero();  // of P_n, right perturbation
};

/// The frame-to-frame edge in the fusion: its covariance Σ_f, the information H_c the fusion gave
/// the chain (zero: not fused) and T̄_m^{n-1}, where the chain starts.
struct ChainTerm {
  core::Matrix6d covariance;
  core::Matrix6d information;
  core::SE3 T_m_previous;
};

/// Frame n tracked against keyframe m: T̄_m^n published, the keyframe edge's covariance and the
/// information the fusion gave it, and the chain when it was fused. Advances `chain`.
PoseCovariances track_against_keyframe(PoseCovarianceChain& chain, const core::SE3& T_mn,
                                       const core::Matrix6d& keyframe_covariance,
                                       const core::Matrix6d& keyframe_information,
                                       const std::optional<ChainTerm>& chain_term);

/// Frame n-1 became the keyframe, frame n measured against it by T_f with covariance Σ_f.
PoseCovariances track_from_new_keyframe(PoseCovarianceChain& chain, const core::SE3& T_f,
                                        const core::Matrix6d& frame_covariance);

/// A frame that starts a keyframe by itself (the first, a restart) or is predicted: nothing
/// measured. `first`: the session's first frame (Σ_O = 0).
PoseCovariances track_unmeasured(PoseCovarianceChain& chain, bool first, bool starts_keyframe);

/// Σ of T exp(ξ) from a left covariance of T: Ad(T)⁻¹ Σ Ad(T)⁻ᵀ.
core::Matrix6d left_to_right(const core::SE3& T, const core::Matrix6d& left);

/// Σ_map(n) above. `keyframe_T_frame` is Δ = T_k^n.
core::Matrix6d map_pose_covariance(const core::Matrix6d& keyframe_map_cov, const core::Matrix6d& keyframe_odometry_cov,
                                   const core::Matrix6d& frame_odometry_cov, const core::SE3& keyframe_T_frame);

}  // namespace cvo::odometry
