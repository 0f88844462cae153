// RANSAC + Umeyama on synthetic 3-D correspondences with a known rigid transform.
#include "libcvo/loop_closure/rigid_ransac.hpp"

#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace cvo::loop_closure {
namespace {

double deg(double rad) { return rad * 180.0 / std::numbers::pi; }

struct Correspondences {
  std::vector<Eigen::Vector3d> src, dst;
  std::vector<bool> inlier;
};

// n points in a 2 x 2 x 3 m box in front of a camera; a fraction `outliers` of them get a dst drawn
// anywhere in the box instead of T src + noise (sigma per axis).
Correspondences make_correspondences(const core::SE3& T, std::size_t n, double outliers, double sigma,
                                     std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-1.0, 1.0), z(1.0, 4.0), u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma);
  Correspondences c;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d p(x(rng), x(rng), z(rng));
    const bool in = u(rng) >= outliers;
    c.src.push_back(p);
    c.dst.push_back(in ? Eigen::Vector3d(T * p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)))
                       : Eigen::Vector3d(x(rng), x(rng), z(rng)));
    c.inlier.push_back(in);
  }
  return c;
}

const core::SE3 kTruth = core::SE3::exp((core::Vector6d() << 0.3, -0.2, 0.5, 0.15, -0.35, 0.2).finished());

TEST(RigidRansac, UmeyamaIsExactOnNoiseFreeCorrespondences) {
  const auto c = make_correspondences(kTruth, 20, 0.0, 0.0, 1);
  const auto T = fit_rigid(c.src, c.dst);
  ASSERT_TRUE(T.has_value());
  const auto e = kTruth.inverse() * *T;
  EXPECT_LT(e.translation().norm(), 1e-9);
  EXPECT_LT(e.angle(), 1e-9);
  EXPECT_FALSE(fit_rigid(c.src, c.dst, {0, 1}).has_value());  // 2 points do not fix a rotation
}

TEST(RigidRansac, RecoversATransformFromCorrespondencesWithFortyPercentOutliers) {
  const auto c = make_correspondences(kTruth, 200, 0.4, 0.004, 7);
  std::size_t true_inliers = 0;
  for (const bool in : c.inlier) true_inliers += in ? 1 : 0;

  // Least squares over everything is far off: the outliers matter.
  const auto plain = kTruth.inverse() * *fit_rigid(c.src, c.dst);
  EXPECT_GT(plain.translation().norm() + plain.angle(), 0.1);

  const RigidFit fit = ransac_rigid(c.src, c.dst, core::LoopVerificationParameters{});
  ASSERT_TRUE(fit.found);
  const auto e = kTruth.inverse() * fit.transform;
  std::printf("true inliers %zu, found %zu; error %.2f mm, %.3f deg; rms %.2f mm\n", true_inliers, fit.inliers.size(),
              1e3 * e.translation().norm(), deg(e.angle()), 1e3 * fit.rms_m);
  // 4 mm noise per axis on ~120 points: the least-squares refit is good to ~1 mm and ~0.05°.
  EXPECT_LT(e.translation().norm(), 0.003);
  EXPECT_LT(deg(e.angle()), 0.15);
  std::size_t wrong = 0, right = 0;
  for (const auto k : fit.inliers) (c.inlier[k] ? right : wrong) += 1;
  EXPECT_GE(right, true_inliers - 2);  // 3 cm is ~4 sigma of the 3-D noise (~7 mm)
  EXPECT_LE(wrong, 2u);                // an outlier may land within 3 cm by chance
  EXPECT_LT(fit.rms_m, 0.01);
}

TEST(RigidRansac, IsDeterministicForAGivenSeed) {
  const auto c = make_correspondences(kTruth, 100, 0.4, 0.004, 3);
  const RigidFit a = ransac_rigid(c.src, c.dst, core::LoopVerificationParameters{});
  const RigidFit b = ransac_rigid(c.src, c.dst, core::LoopVerificationParameters{});
  ASSERT_TRUE(a.found);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.transform.matrix(), b.transform.matrix());
}

TEST(RigidRansac, RefusesUnrelatedPointsAndTooFewCorrespondences) {
  // Only outliers: no 3-point model gathers 12 inliers within 3 cm in a 12 m³ box.
  const auto c = make_correspondences(kTruth, 200, 1.0, 0.0, 5);
  const RigidFit fit = ransac_rigid(c.src, c.dst, core::LoopVerificationParameters{});
  EXPECT_FALSE(fit.found);
  EXPECT_TRUE(fit.inliers.empty());

  const auto few = make_correspondences(kTruth, 2, 0.0, 0.0, 6);
  EXPECT_FALSE(ransac_rigid(few.src, few.dst, core::LoopVerificationParameters{.min_inliers = 0}).found);
  // Clean but fewer than min_inliers.
  const auto some = make_correspondences(kTruth, 10, 0.0, 0.001, 8);
  EXPECT_FALSE(ransac_rigid(some.src, some.dst, core::LoopVerificationParameters{}).found);
  EXPECT_TRUE(ransac_rigid(some.src, some.dst, core::LoopVerificationParameters{.min_inliers = 8}).found);
  // Mismatched sizes.
  auto bad = some;
  bad.dst.pop_back();
  EXPECT_FALSE(ransac_rigid(bad.src, bad.dst, core::LoopVerificationParameters{.min_inliers = 3}).found);
}

}  // namespace
}  // namespace cvo::loop_closure
