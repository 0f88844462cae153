#pragma once
// The residual of one edge and its Jacobians.
//
// Residual:  e = log(E),  E = Z^-1 T_i^-1 T_j,  Z the measured T_ij; e = [rho; phi] as core::SE3.
//
// Perturbation: RIGHT, T <- T exp(delta), delta = [translation; rotation] in the node's own frame.
// With the right Jacobian J_r of SE(3) (exp(xi + d) ~ exp(xi) exp(J_r(xi) d)):
//   T_j exp(d):  E exp(d)                          =>  de/dd_j =  J_r^-1(e)
//   T_i exp(d):  Z^-1 exp(-d) T_i^-1 T_j = E exp(-Ad(E^-1 Z^-1) d) = E exp(-Ad(T_j^-1 T_i) d)
//                                                  =>  de/dd_i = -J_r^-1(e) Ad(T_j^-1 T_i)
// J_r^-1 is the exact closed form (Barfoot, "State Estimation for Robotics", 7.1.5), not the
// first-order I + 1/2 ad(e): the large residuals of torus/sphere initial guesses need it.
#include "libcvo/core/se3.hpp"

namespace cvo::posegraph {

/// e = log(Z^-1 T_i^-1 T_j).
core::Vector6d edge_residual(const core::SE3& T_i, const core::SE3& T_j, const core::SE3& Z);

/// ad(xi) = [[phi^, rho^], [0, phi^]], the matrix with [xi, v] = ad(xi) v.
core::Matrix6d small_adjoint(const core::Vector6d& xi);

/// Inverse right Jacobian of SE(3) at xi = [rho; phi]; J_r^-1(xi) = J_l^-1(-xi).
core::Matrix6d right_jacobian_inverse(const core::Vector6d& xi);

struct EdgeLinearisation {
  core::Vector6d residual;
  core::Matrix6d jacobian_i;  // de/d delta_i
  core::Matrix6d jacobian_j;  // de/d delta_j
};

EdgeLinearisation linearise_edge(const core::SE3& T_i, const core::SE3& T_j, const core::SE3& Z);

}  // namespace cvo::posegraph
