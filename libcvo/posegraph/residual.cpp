#include "libcvo/posegraph/residual.hpp"

#include <cmath>

namespace cvo::posegraph {
namespace {

using core::hat;
using core::so3_left_jacobian_inverse;

// Below this angle the closed-form coefficients lose digits to cancellation; their Taylor series
// (two terms) are exact to double precision there.
constexpr double kSmallAngle = 1e-3;

// The coupling block Q(rho, phi) of the SE(3) left Jacobian [[J, Q], [0, J]] (Barfoot 7.86).
Eigen::Matrix3d left_jacobian_q(const Eigen::Vector3d& rho, const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  const double th2 = th * th;
  double c1 = 0, c2 = 0, c3 = 0;
  if (th < kSmallAngle) {
    c1 = 1.0 / 6.0 - th2 / 120.0;
    c2 = 1.0 / 24.0 - th2 / 720.0;
    c3 = 1.0 / 120.0 - th2 / 2520.0;
  } else {
    const double s = std::sin(th);
    const double c = std::cos(th);
    c1 = (th - s) / (th2 * th);
    c2 = (th2 + 2.0 * c - 2.0) / (2.0 * th2 * th2);
    c3 = (2.0 * th - 3.0 * s + th * c) / (2.0 * th2 * th2 * th);
  }
  const Eigen::Matrix3d P = hat(phi);
  const Eigen::Matrix3d R = hat(rho);
  const Eigen::Matrix3d PR = P * R;
  const Eigen::Matrix3d RP = R * P;
  const Eigen::Matrix3d PRP = PR * P;
  return 0.5 * R + c1 * (PR + RP + PRP) + c2 * (P * PR + RP * P - 3.0 * PRP) + c3 * (PRP * P + P * PRP);
}

}  // namespace

core::Vector6d edge_residual(const core::SE3& T_i, const core::SE3& T_j, const core::SE3& Z) {
  return (Z.inverse() * T_i.inverse() * T_j).log();
}

core::Matrix6d small_adjoint(const core::Vector6d& xi) {
  core::Matrix6d ad = core::Matrix6d::Zero();
  const Eigen::Matrix3d P = hat(xi.tail<3>());
  ad.topLeftCorner<3, 3>() = P;
  ad.topRightCorner<3, 3>() = hat(xi.head<3>());
  ad.bottomRightCorner<3, 3>() = P;
  return ad;
}

core::Matrix6d right_jacobian_inverse(const core::Vector6d& xi) {
  // J_l^-1 = [[J^-1, -J^-1 Q J^-1], [0, J^-1]], evaluated at -xi.
  const Eigen::Vector3d rho = -xi.head<3>();
  const Eigen::Vector3d phi = -xi.tail<3>();
  const Eigen::Matrix3d Jinv = so3_left_jacobian_inverse(phi);
  core::Matrix6d out = core::Matrix6d::Zero();
  out.topLeftCorner<3, 3>() = Jinv;
  out.topRightCorner<3, 3>() = -Jinv * left_jacobian_q(rho, phi) * Jinv;
  out.bottomRightCorner<3, 3>() = Jinv;
  return out;
}

EdgeLinearisation linearise_edge(const core::SE3& T_i, const core::SE3& T_j, const core::SE3& Z) {
  EdgeLinearisation lin;
  lin.residual = edge_residual(T_i, T_j, Z);
  const core::Matrix6d Jr_inv = right_jacobian_inverse(lin.residual);
  lin.jacobian_j = Jr_inv;
  lin.jacobian_i = -Jr_inv * (T_j.inverse() * T_i).adjoint();
  return lin;
}

}  // namespace cvo::posegraph
