#pragma once
// Rigid alignment of two corresponding point sets without scale: Horn's closed-form absolute
// orientation in the SVD form of Umeyama, as evaluate_ate.py's align() computes it.
//
// Finds the rotation R and translation t minimising  sum_i |R m_i + t - d_i|^2  (m = model,
// d = data):
//   m_c, d_c    the centroids of the model and data points
//   H = sum_i (d_i - d_c)(m_i - m_c)^T = U S V^T
//   R = U diag(1, 1, s) V^T   with s = -1 when det(U) det(V) < 0, else 1: the guard keeps R a
//                             proper rotation where the unconstrained optimum is a reflection
//   t = d_c - R m_c
// For degenerate point sets (all on one line, or all equal) R is not unique; any minimiser is
// returned, and the residuals are the same for all of them.
#include <span>

#include <Eigen/Core>

#include "libcvo/core/se3.hpp"

namespace cvo::eval {

/// The transform T with T * model[i] ~ data[i]. Throws std::invalid_argument when the lists are
/// empty or differ in length.
core::SE3 align_rigid(std::span<const Eigen::Vector3d> model, std::span<const Eigen::Vector3d> data);

}  // namespace cvo::eval
