#include "libcvo/eval/alignment.hpp"

#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace cvo::eval {
namespace {

std::vector<Eigen::Vector3d> random_points(std::size_t n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  std::vector<Eigen::Vector3d> p(n);
  for (auto& v : p) v = {u(rng), u(rng), u(rng)};
  return p;
}

TEST(AteAlignment, RecoversAKnownRigidTransform) {
  const core::SE3 truth = core::SE3::exp((core::Vector6d() << 3, -1, 0.5, 0.4, -1.2, 2.0).finished());
  const auto model = random_points(20);
  std::vector<Eigen::Vector3d> data;
  for (const auto& m : model) data.push_back(truth * m);
  const core::SE3 found = align_rigid(model, data);
  EXPECT_TRUE(found.matrix().isApprox(truth.matrix(), 1e-12)) << found.matrix();
}

TEST(AteAlignment, MirrorImageGivesARotationNotAReflection) {
  const auto model = random_points(20);
  std::vector<Eigen::Vector3d> data;
  for (const auto& m : model) data.emplace_back(-m.x(), m.y(), m.z());
  const core::SE3 found = align_rigid(model, data);
  EXPECT_NEAR(found.rotation_matrix().determinant(), 1.0, 1e-12);
}

TEST(AteAlignment, MismatchedOrEmptyListsAreErrors) {
  EXPECT_THROW(align_rigid(random_points(3), random_points(4)), std::invalid_argument);
  EXPECT_THROW(align_rigid({}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::eval
