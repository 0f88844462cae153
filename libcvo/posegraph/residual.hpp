#pragma once
// The residual of one edge, the retraction that updates a node, and the edge's Jacobians.
//
// Residual: with E = Z^-1 T_i^-1 T_j (Z the measured T_ij) and q_E its unit quaternion taken with
// w >= 0,
//   e = [t_E; 2 vec(q_E)]                                  (translation first, as core::SE3's xi)
// the formulation of Ceres' pose_graph_3d example. To first order it is log(E), so information
// matrices meant for the SE(3) logarithm (CVO Hessians, g2o files) weight it correctly. Away from
// zero it differs in the two ways that matter on graphs whose initial guess is far off (torus3D):
// |2 vec(q_E)| = 2 sin(theta/2) levels off instead of growing like theta, so edges with a large
// rotation error pull less hard while the rest of the graph settles; and the translation error is
// not bent by the rotation error (log(E) has V^-1(phi) t_E). With log(E), LM stops short of Ceres'
// cost on torus3D; with this residual it reaches it (libcvo/posegraph/README.md, "The residual").
//
// Retraction: T (+) d = (R exp(phi), t + R rho), d = [rho; phi] in the node's own frame; to first
// order it is T exp(d).
//
// Jacobians (A = T_i^-1 T_j, so t_A = R_i^T (t_j - t_i) and R_E = R_z^T R_A; q_E = (w, v)):
//   d(2 vec q_E)/d phi for q_E <- q_E exp(phi) is  Q = w I + v^
//   de/dd_j = [[R_E, 0], [0, Q]]
//   de/dd_i = [[-R_z^T, R_z^T t_A^], [0, -Q R_A^T]]      (R_i exp(phi) gives R_E exp(-R_A^T phi))
#include "libcvo/core/se3.hpp"

namespace cvo::posegraph {

/// e = [t_E; 2 vec(q_E)], E = Z^-1 T_i^-1 T_j, q_E with w >= 0.
core::Vector6d edge_residual(const core::SE3& T_i, const core::SE3& T_j, const core::SE3& Z);

/// T (+) d = (R exp(phi), t + R rho), d = [rho; phi].
core::SE3 retract(const core::SE3& T, const core::Vector6d& d);

struct EdgeLinearisation {
  core::Vector6d residual;
  core::Matrix6d jacobian_i;  // de/d d_i
  core::Matrix6d jacobian_j;  // de/d d_j
};

EdgeLinearisation linearise_edge(const core::SE3& T_i, const core::SE3& T_j, const core::SE3& Z);

}  // namespace cvo::posegraph
