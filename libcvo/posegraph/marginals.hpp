#pragma once
// The marginal covariances of a pose graph's nodes: the Laplace (Gauss-Newton) approximation at
// the graph's current poses, as the optimiser left them.
//
// With every edge linearised as the optimiser linearises it (residual.hpp) and weighted as it
// weights it (robust edges at their IRLS weight w = rho'(chi²), cost.hpp), the information of the
// free poses is H = Σ w Jᵀ Ω J and their covariance H⁻¹; node k's marginal is the 6x6 diagonal
// block of H⁻¹ at its variables, a perturbation of the retraction T (+) d ≈ T exp(d) (on the
// right, [rho; phi] as core::SE3). Fixed nodes are constants: their marginal is zero, and they
// condition the rest (when no node is fixed the first is held, the optimiser's gauge). Only as
// honest as the edges' information: the tracker's is calibrated (registration/edge_covariance.hpp).
//
// Cost: one sparse Cholesky factorisation of H (Eigen's SimplicialLLT, AMD ordering), then six
// solves per requested node, in batches.
#include <map>
#include <vector>

#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {

/// The marginal covariance of each of `nodes`. Throws std::out_of_range for an id not in the
/// graph, std::runtime_error when H is not positive definite (a free node no edge constrains).
std::map<NodeId, core::Matrix6d> marginal_covariances(const PoseGraph& graph, const std::vector<NodeId>& nodes,
                                                      const OptimizerOptions& options = {});

}  // namespace cvo::posegraph
