#include "libcvo/posegraph/residual.hpp"

#include <random>

#include <gtest/gtest.h>

namespace cvo::posegraph {
namespace {

using core::Matrix6d;
using core::SE3;
using core::Vector6d;

Vector6d random_xi(std::mt19937& rng, double translation, double angle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vector6d xi;
  for (int k = 0; k < 3; ++k) xi[k] = translation * u(rng);
  Eigen::Vector3d axis(u(rng), u(rng), u(rng));
  xi.tail<3>() = angle * axis.normalized();
  return xi;
}

// Central differences of the residual under right perturbations of T_i and T_j.
void numeric_jacobians(const SE3& Ti, const SE3& Tj, const SE3& Z, Matrix6d& Ji, Matrix6d& Jj) {
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    const Vector6d d = Vector6d::Unit(k) * h;
    Ji.col(k) = (edge_residual(Ti * SE3::exp(d), Tj, Z) - edge_residual(Ti * SE3::exp(-d), Tj, Z)) / (2 * h);
    Jj.col(k) = (edge_residual(Ti, Tj * SE3::exp(d), Z) - edge_residual(Ti, Tj * SE3::exp(-d), Z)) / (2 * h);
  }
}

TEST(Residual, ZeroForAConsistentMeasurement) {
  const SE3 Ti = SE3::exp((Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const SE3 Tj = SE3::exp((Vector6d() << -1, 0, 2, -0.4, 0.2, 1.3).finished());
  EXPECT_LT(edge_residual(Ti, Tj, Ti.inverse() * Tj).norm(), 1e-12);
}

TEST(Residual, AnalyticJacobiansMatchNumericOnes) {
  std::mt19937 rng(7);
  // Residual angles from tiny (the Taylor branch) to nearly pi (where J_r^-1 is far from I).
  for (const double residual_angle : {0.0, 1e-5, 1e-3, 0.1, 1.0, 2.0, 2.8}) {
    for (int trial = 0; trial < 5; ++trial) {
      const SE3 Ti = SE3::exp(random_xi(rng, 5.0, 2.0));
      const SE3 Tj = SE3::exp(random_xi(rng, 5.0, 2.0));
      const SE3 error = SE3::exp(random_xi(rng, 1.0, residual_angle));
      const SE3 Z = Ti.inverse() * Tj * error.inverse();  // so that Z^-1 Ti^-1 Tj == error
      const auto lin = linearise_edge(Ti, Tj, Z);
      Matrix6d Ji, Jj;
      numeric_jacobians(Ti, Tj, Z, Ji, Jj);
      EXPECT_LT((lin.jacobian_i - Ji).cwiseAbs().maxCoeff(), 1e-6) << "angle " << residual_angle;
      EXPECT_LT((lin.jacobian_j - Jj).cwiseAbs().maxCoeff(), 1e-6) << "angle " << residual_angle;
    }
  }
}

TEST(Residual, RightJacobianInverseIsTheFirstOrderFormNearZero) {
  const Vector6d xi = (Vector6d() << 1e-4, -2e-4, 3e-4, 2e-4, 1e-4, -1e-4).finished();
  const Matrix6d approx = Matrix6d::Identity() + 0.5 * small_adjoint(xi);
  EXPECT_LT((right_jacobian_inverse(xi) - approx).cwiseAbs().maxCoeff(), 1e-7);
}

}  // namespace
}  // namespace cvo::posegraph
