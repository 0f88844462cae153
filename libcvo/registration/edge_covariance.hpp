#pragma once
// The covariance of a CVO registration's result: the one calibration of the project (the tracker's
// local graph edges, the published poses' covariances and the back end's weights all take it).
//
// What the CVO Hessian is not. RegistrationResult::hessian, H = Σ_j A_j J_jᵀ J_j / ℓ², is the
// Gauss-Newton curvature of a kernel correlation F, not of a log-likelihood: it grows with the
// kernel amplitudes (σ², σ_c²), with the density of the fixed cloud (pairs per moving point) and
// as 1/ℓ², ℓ a length chosen for the basin of convergence, not the sensor's noise. Its inverse is
// therefore off by a factor that differs from scene to scene and from sensor to sensor, and no
// constant fixes that.
//
// What is. The estimate T̂ is an M-estimator: the root of Σ_j g_j(T) = 0, g_j the moving point j's
// term of ∇F. To first order δξ = H⁻¹ Σ_j g_j, so
//   Σ = H⁻¹ B H⁻¹,   B = Cov(Σ_j g_j) ≈ Σ_c G_c G_cᵀ       (Huber 1967, White 1980: the sandwich)
// with the cluster sums G_c of RegistrationResult::gradient_scatter (registration.hpp: clusters of
// neighbouring points, whose terms are correlated). Every amplitude cancels (H scales as a, B as
// a²), the length-scale's choice enters only through what the points really show, and the scatter
// is measured on each pair of clouds: depth noise that grows with distance, blur, texture and
// structure all enter B as they are. Nothing of it is fitted to a sequence, so it carries to
// sequences we do not have; the figures (NEES on rendered and real sequences, the cluster size):
// bench/odometry-tuning.md, "Covariance".
//
// Convention: a LEFT perturbation in the fixed cloud's frame, T_true = exp(ξ) T̂, ξ ~ N(0, Σ), in
// [translation; rotation] (RegistrationResult::hessian's; pose_covariance.hpp converts).
#include <optional>

#include "libcvo/core/se3.hpp"
#include "libcvo/registration/registration.hpp"

namespace cvo::registration {

/// H⁻¹ B H⁻¹ of a converged registration, symmetric; nullopt when H is singular or the result
/// not finite (a registration that constrains fewer than six directions has no covariance).
std::optional<core::Matrix6d> edge_covariance(const RegistrationResult& result);

/// The information Σ⁻¹ of an edge with (calibrated) covariance Σ, for a pose graph in the
/// registration's convention; the CVO Hessian itself when there is none (a degenerate
/// registration keeps its zero directions, which core::check_information accepts).
core::Matrix6d information_of(const std::optional<core::Matrix6d>& covariance, const core::Matrix6d& hessian);

}  // namespace cvo::registration
