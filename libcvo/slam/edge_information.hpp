#pragma once
// The information matrix of a pose-graph edge measured by a CVO registration.
//
// A registration of a moving cloud (frame j) onto a fixed one (frame i) reports H, the
// Gauss-Newton Hessian of its objective for a LEFT perturbation of its result Z = T_ij in frame
// i's coordinates: Z_true = exp(ξ) Z, ξ ~ N(0, H⁻¹) (registration.hpp). The pose graph's residual
// is, to first order, e = log(Z⁻¹ T_i⁻¹ T_j) (pose_graph.hpp), a perturbation on the RIGHT, in frame j's
// coordinates. At the truth e = log(Z⁻¹ exp(ξ) Z) = Ad(Z⁻¹) ξ, so e ~ N(0, Ad(Z⁻¹) H⁻¹ Ad(Z⁻¹)ᵀ)
// and its information is
//   Ω = Ad(Z)ᵀ H Ad(Z).
// For a small motion Ad(Z) ≈ I; across a keyframe's 30° / 15 cm, or a loop, it matters.
#include "libcvo/core/se3.hpp"

namespace cvo::slam {

/// Ω = Ad(Z)ᵀ H Ad(Z), made exactly symmetric (posegraph::PoseGraph::add_edge checks).
core::Matrix6d edge_information(const core::SE3& measurement, const core::Matrix6d& cvo_hessian);

}  // namespace cvo::slam
