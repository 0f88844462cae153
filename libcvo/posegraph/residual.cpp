#include "libcvo/posegraph/residual.hpp"

namespace cvo::posegraph {

using core::hat;
using core::SE3;
using core::Vector6d;

namespace {

// q and -q are the same rotation; w >= 0 picks the one whose vector part is small near identity.
Eigen::Quaterniond canonical(Eigen::Quaterniond q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

}  // namespace

Vector6d edge_residual(const SE3& T_i, const SE3& T_j, const SE3& Z) {
  const SE3 E = Z.inverse() * T_i.inverse() * T_j;
  Vector6d e;
  e << E.translation(), 2.0 * canonical(E.rotation()).vec();
  return e;
}

SE3 retract(const SE3& T, const Vector6d& d) {
  return {T.rotation() * core::so3_exp(d.tail<3>()), T.translation() + T.rotation() * d.head<3>()};
}

EdgeLinearisation linearise_edge(const SE3& T_i, const SE3& T_j, const SE3& Z) {
  const SE3 A = T_i.inverse() * T_j;
  const Eigen::Quaterniond q_E = canonical(Z.rotation().conjugate() * A.rotation());
  const Eigen::Matrix3d Rz_t = Z.rotation_matrix().transpose();
  const Eigen::Matrix3d R_A = A.rotation_matrix();
  const Eigen::Matrix3d Q = q_E.w() * Eigen::Matrix3d::Identity() + hat(q_E.vec());
  EdgeLinearisation lin;
  lin.residual << Rz_t * (A.translation() - Z.translation()), 2.0 * q_E.vec();
  lin.jacobian_j.setZero();
  lin.jacobian_j.topLeftCorner<3, 3>() = Rz_t * R_A;
  lin.jacobian_j.bottomRightCorner<3, 3>() = Q;
  lin.jacobian_i.setZero();
  lin.jacobian_i.topLeftCorner<3, 3>() = -Rz_t;
  lin.jacobian_i.topRightCorner<3, 3>() = Rz_t * hat(A.translation());
  lin.jacobian_i.bottomRightCorner<3, 3>() = -Q * R_A.transpose();
  return lin;
}

}  // namespace cvo::posegraph
