#include "libcvo/posegraph/residual.hpp"

#include <cmath>
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
    Ji.col(k) = (edge_residual(retract(Ti, d), Tj, Z) - edge_residual(retract(Ti, -d), Tj, Z)) / (2 * h);
    Jj.col(k) = (edge_residual(Ti, retract(Tj, d), Z) - edge_residual(Ti, retract(Tj, -d), Z)) / (2 * h);
  }
}

TEST(Residual, ZeroForAConsistentMeasurement) {
  const SE3 Ti = SE3::exp((Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const SE3 Tj = SE3::exp((Vector6d() << -1, 0, 2, -0.4, 0.2, 1.3).finished());
  EXPECT_LT(edge_residual(Ti, Tj, Ti.inverse() * Tj).norm(), 1e-12);
}

TEST(Residual, AnalyticJacobiansMatchNumericOnes) {
  std::mt19937 rng(7);
  // Residual angles from zero to nearly pi (where the Jacobians are far from the identity).
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

// The residual keeps translation and rotation apart (the SE(3) logarithm would mix the rotation
// into the translation part, V^-1(phi) t), and its rotation part is 2 sin(theta/2) along the axis.
TEST(Residual, IsTheErrorTranslationAndQuaternionVector) {
  const SE3 Ti = SE3::exp((Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const SE3 Tj = SE3::exp((Vector6d() << -1, 0, 2, -0.4, 0.2, 1.3).finished());
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.2, 0.5).normalized();
  for (const double angle : {0.2, 2.0, 3.1}) {
    const SE3 error(core::so3_exp(angle * axis), Eigen::Vector3d(0.1, 0.2, -0.3));
    const SE3 Z = Ti.inverse() * Tj * error.inverse();
    const Vector6d e = edge_residual(Ti, Tj, Z);
    EXPECT_LT((e.head<3>() - Eigen::Vector3d(0.1, 0.2, -0.3)).norm(), 1e-12);
    EXPECT_LT((e.tail<3>() - 2 * std::sin(angle / 2) * axis).norm(), 1e-12) << "angle " << angle;
  }
}

// Near zero it is the SE(3) logarithm, so information matrices meant for log(E) apply.
TEST(Residual, IsTheLogarithmToFirstOrder) {
  const SE3 Ti = SE3::exp((Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const SE3 Tj = SE3::exp((Vector6d() << -1, 0, 2, -0.4, 0.2, 1.3).finished());
  const Vector6d xi = (Vector6d() << 1e-4, -2e-4, 3e-4, 2e-4, 1e-4, -1e-4).finished();
  const SE3 Z = Ti.inverse() * Tj * SE3::exp(xi).inverse();
  EXPECT_LT((edge_residual(Ti, Tj, Z) - xi).norm(), 1e-7);
}

TEST(Residual, RetractionIsExpToFirstOrder) {
  const SE3 T = SE3::exp((Vector6d() << 1, -2, 3, 0.4, 0.2, -0.3).finished());
  const Vector6d d = (Vector6d() << 1e-5, 2e-5, -1e-5, 3e-5, -2e-5, 1e-5).finished();
  const SE3 a = retract(T, d);
  const SE3 b = T * SE3::exp(d);
  EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9);
  EXPECT_LT(a.rotation().angularDistance(b.rotation()), 1e-9);
}

}  // namespace
}  // namespace cvo::posegraph
