#include "libcvo/core/se3.hpp"

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

namespace cvo::core {
namespace {

Vector6d random_xi(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Vector3d axis(u(rng), u(rng), u(rng));
  axis.normalize();
  const double angle = max_angle * std::abs(u(rng));
  Vector6d xi;
  xi << u(rng), u(rng), u(rng), angle * axis;
  return xi;
}

void expect_near(const SE3& a, const SE3& b, double tol) {
  EXPECT_TRUE(a.matrix().isApprox(b.matrix(), tol)) << "a=\n" << a.matrix() << "\nb=\n" << b.matrix();
}

TEST(SE3, ExpLogRoundTripIncludingSmallAndNearPiAngles) {
  std::mt19937 rng(7);
  for (const double max_angle : {1e-9, 1e-6, 1e-3, 1.0, 3.0, std::numbers::pi - 1e-6}) {
    for (int k = 0; k < 200; ++k) {
      const Vector6d xi = random_xi(rng, max_angle);
      const Vector6d back = SE3::exp(xi).log();
      EXPECT_TRUE(back.isApprox(xi, 1e-7) || (back - xi).norm() < 1e-12)
          << xi.transpose() << " vs " << back.transpose();
    }
  }
}

TEST(SE3, ExpMatchesMatrixExponentialOfTwist) {
  // exp of the 4x4 twist matrix by a long Taylor series: an independent check of V(phi).
  Vector6d xi;
  xi << 0.3, -0.2, 0.5, 0.4, -0.7, 0.2;
  Eigen::Matrix4d X = Eigen::Matrix4d::Zero();
  X.topLeftCorner<3, 3>() = hat(xi.tail<3>());
  X.topRightCorner<3, 1>() = xi.head<3>();
  Eigen::Matrix4d sum = Eigen::Matrix4d::Identity(), term = Eigen::Matrix4d::Identity();
  for (int n = 1; n < 40; ++n) {
    term = term * X / n;
    sum += term;
  }
  EXPECT_TRUE(SE3::exp(xi).matrix().isApprox(sum, 1e-12));
}

TEST(SE3, ComposeInverseAndActOnPoints) {
  std::mt19937 rng(3);
  for (int k = 0; k < 100; ++k) {
    const SE3 a = SE3::exp(random_xi(rng, 3.0));
    const SE3 b = SE3::exp(random_xi(rng, 3.0));
    const Eigen::Vector3d p(0.3, -1.0, 2.0);
    EXPECT_TRUE((a * b).matrix().isApprox(a.matrix() * b.matrix(), 1e-12));
    expect_near(a * a.inverse(), SE3(), 1e-12);
    EXPECT_TRUE(((a * b) * p).isApprox(a * (b * p), 1e-12));
    EXPECT_TRUE((a * p).isApprox((a.matrix() * p.homogeneous()).head<3>(), 1e-12));
  }
}

TEST(SE3, AdjointMovesTangentVectorsAcrossTheTransform) {
  std::mt19937 rng(11);
  const SE3 T = SE3::exp(random_xi(rng, 2.0));
  Vector6d xi = random_xi(rng, 0.5);
  expect_near(SE3::exp(T.adjoint() * xi), T * SE3::exp(xi) * T.inverse(), 1e-10);
}

TEST(SE3, InterpolationIsGeodesic) {
  const SE3 a = SE3::exp((Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const SE3 b = SE3::exp((Vector6d() << 1.5, 2, 2, -0.4, 0.2, 0.9).finished());
  expect_near(interpolate(a, b, 0.0), a, 1e-12);
  expect_near(interpolate(a, b, 1.0), b, 1e-12);
  // Half-way: the same relative motion from a to the middle as from the middle to b.
  const SE3 m = interpolate(a, b, 0.5);
  expect_near(a.inverse() * m, m.inverse() * b, 1e-10);
  // Pure translation interpolates linearly.
  const SE3 ta = SE3::from_translation({0, 0, 0}), tb = SE3::from_translation({2, -4, 6});
  EXPECT_TRUE(interpolate(ta, tb, 0.25).translation().isApprox(Eigen::Vector3d(0.5, -1, 1.5)));
}

TEST(SE3, AngleAndMatrixConstructorRepairsNearRotations) {
  const SE3 r = SE3::from_rotation_vector({0, 0, 0.5});
  EXPECT_NEAR(r.angle(), 0.5, 1e-12);
  Eigen::Matrix4d m = r.matrix();
  m(0, 0) += 1e-7;  // slightly non-orthonormal, as after text round trips
  const SE3 repaired(m);
  EXPECT_NEAR(repaired.rotation().norm(), 1.0, 1e-12);
  EXPECT_NEAR(repaired.angle(), 0.5, 1e-6);
  // q and -q are the same rotation; log must pick the short way.
  const SE3 neg(Eigen::Quaterniond(-r.rotation().coeffs()), Eigen::Vector3d::Zero());
  EXPECT_NEAR(neg.angle(), 0.5, 1e-12);
}

TEST(SE3, FiniteCheck) {
  EXPECT_TRUE(SE3().is_finite());
  EXPECT_FALSE(SE3::from_translation({0, std::nan(""), 0}).is_finite());
}

}  // namespace
}  // namespace cvo::core
