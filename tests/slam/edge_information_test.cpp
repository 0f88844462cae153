#include "libcvo/slam/edge_information.hpp"

#include <gtest/gtest.h>

namespace cvo::slam {
namespace {

// A registration's left perturbation ξ of T_ij (Z_true = exp(ξ) Z) is the pose-graph residual
// e = log(Z⁻¹ exp(ξ) Z) = Ad(Z⁻¹) ξ exactly; its χ² under Ω must be ξᵀ H ξ, whatever Z is.
TEST(EdgeInformation, ChiSquaredOfTheResidualIsTheRegistrationsOwn) {
  const core::SE3 Z = core::SE3::exp((core::Vector6d() << 0.12, -0.05, 0.08, 0.2, -0.4, 0.5).finished());
  core::Matrix6d A;
  A << 3, 1, 0, 0, 2, 0, 0, 4, 1, 0, 0, 1, 1, 0, 5, 1, 0, 0, 0, 2, 0, 6, 1, 0, 1, 0, 0, 1, 7, 2, 0, 1, 2, 0, 1, 8;
  const core::Matrix6d H = 100 * A.transpose() * A;  // symmetric positive definite
  const core::Matrix6d omega = edge_information(Z, H);
  EXPECT_EQ(omega, omega.transpose());
  for (int k = 0; k < 6; ++k) {
    const core::Vector6d xi = 1e-2 * core::Vector6d::Unit(k) + 3e-3 * core::Vector6d::Ones();
    const core::Vector6d e = (Z.inverse() * core::SE3::exp(xi) * Z).log();
    EXPECT_NEAR(e.dot(omega * e), xi.dot(H * xi), 1e-6 * xi.dot(H * xi)) << k;
  }
  // No motion: nothing to convert.
  EXPECT_TRUE(edge_information(core::SE3(), H).isApprox(H, 1e-12));
}

}  // namespace
}  // namespace cvo::slam
