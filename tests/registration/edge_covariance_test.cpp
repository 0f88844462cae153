#include "libcvo/registration/edge_covariance.hpp"

#include <gtest/gtest.h>

#include "tests/registration/registration_fixtures.hpp"

namespace cvo::registration {
namespace {

const core::SE3 kMotion{core::so3_exp({0.0, 0.03, 0.01}), Eigen::Vector3d(0.015, -0.01, 0.02)};

RegistrationResult align_with(const core::CvoParameters& parameters) {
  const auto pair = testing::render_pair(sim::SceneKind::textured_room, testing::camera_looking_north(), kMotion);
  Registration registration(Capacities{8192}, parameters);
  return registration.align(pair.first, pair.second, core::SE3());
}

// The Hessian grows with the kernel's amplitude σ² σ_c²; the sandwich H⁻¹ B H⁻¹ does not: the
// amplitude is no measurement's noise. (The threshold scales with it, so the same pairs count.)
TEST(EdgeCovariance, DoesNotDependOnTheKernelsAmplitudeAsTheHessianDoes) {
  core::CvoParameters p;
  const RegistrationResult a = align_with(p);
  p.sigma *= 2;
  p.sparsification_threshold *= 4;
  const RegistrationResult b = align_with(p);
  ASSERT_TRUE(a.converged && b.converged);
  EXPECT_NEAR(b.hessian.trace() / a.hessian.trace(), 4.0, 1e-3);
  const auto sa = edge_covariance(a), sb = edge_covariance(b);
  ASSERT_TRUE(sa && sb);
  EXPECT_LT((*sa - *sb).norm(), 1e-3 * sa->norm());
  EXPECT_GT(a.gradient_scatter.trace(), 0);
}

TEST(EdgeCovariance, TheInformationIsItsInverseOrTheHessianWithoutOne) {
  const RegistrationResult r = align_with(core::CvoParameters{});
  const auto sigma = edge_covariance(r);
  ASSERT_TRUE(sigma);
  EXPECT_LT((information_of(sigma, r.hessian) * *sigma - core::Matrix6d::Identity()).norm(), 1e-6);
  EXPECT_EQ(information_of(std::nullopt, r.hessian), r.hessian);
  RegistrationResult singular;  // a zero Hessian: nothing constrained
  EXPECT_FALSE(edge_covariance(singular).has_value());
}

}  // namespace
}  // namespace cvo::registration
