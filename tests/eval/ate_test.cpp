#include "libcvo/eval/ate.hpp"

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "eval/test_trajectories.hpp"
#include "libcvo/io/trajectory_io.hpp"

namespace cvo::eval {
namespace {

using testing::helix;
using testing::kStep;
using testing::make;
using testing::transformed;

TEST(Ate, IdenticalTrajectoriesHaveZeroError) {
  const auto gt = make(40, helix);
  const auto r = absolute_trajectory_error(gt, gt);
  EXPECT_EQ(r.pairs.size(), 40u);
  EXPECT_EQ(r.error.count, 40u);
  EXPECT_NEAR(r.error.rmse, 0, 1e-12);
  EXPECT_NEAR(r.error.max, 0, 1e-12);
  EXPECT_TRUE(r.alignment.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12));
}

TEST(Ate, ConstantTranslationOffsetIsAlignedAway) {
  const auto gt = make(40, helix);
  const auto est = transformed(core::SE3::from_translation({5, -3, 2}), gt);
  const auto r = absolute_trajectory_error(gt, est);
  EXPECT_NEAR(r.error.rmse, 0, 1e-12);
  EXPECT_TRUE(r.alignment.translation().isApprox(Eigen::Vector3d(-5, 3, -2), 1e-12));
}

TEST(Ate, RotationAboutTheOriginIsAlignedAway) {
  const auto gt = make(40, helix);
  const core::SE3 rotation = core::SE3::from_rotation_vector({0.3, -0.8, 1.9});
  const auto r = absolute_trajectory_error(gt, transformed(rotation, gt));
  EXPECT_NEAR(r.error.rmse, 0, 1e-12);
  EXPECT_TRUE(r.alignment.matrix().isApprox(rotation.inverse().matrix(), 1e-12));
}

// Ground truth x = t along a straight line, estimate x = (1 + v) t. No rotation or translation
// can undo a stretch, so the best rigid fit only matches the centroids and leaves v (t - mean t):
// for N stamps h apart, RMSE = |v| h sqrt((N^2 - 1) / 12) and max = |v| h (N - 1) / 2.
TEST(Ate, DriftAlongAStraightLineLeavesTheCentredStretch) {
  constexpr std::size_t n = 41;
  constexpr double v = 0.05;
  const auto gt = make(n, [](double t) { return core::SE3::from_translation({t, 0, 0}); });
  const auto est = make(n, [](double t) { return core::SE3::from_translation({(1 + v) * t, 0, 0}); });
  const auto r = absolute_trajectory_error(gt, est);
  const double nd = static_cast<double>(n);
  EXPECT_NEAR(r.error.rmse, v * kStep * std::sqrt((nd * nd - 1) / 12), 1e-12);
  EXPECT_NEAR(r.error.max, v * kStep * (nd - 1) / 2, 1e-12);
  EXPECT_NEAR(r.error.min, 0, 1e-12);                  // the middle pose is the centroid
  EXPECT_NEAR(r.error.median, v * kStep * 10, 1e-12);  // |k - 20| sorted: the 21st value is 10
}

// Six poses on the axes, one moved by d = 0.3 m away from the centroid. The cross-covariance stays
// symmetric positive definite, so the best rotation is the identity and the alignment only shifts
// by d / N: the moved pose keeps d (N - 1) / N, the others d / N, RMSE = d sqrt(N - 1) / N.
TEST(Ate, OnePerturbedPoseGivesTheHandValue) {
  const std::vector<Eigen::Vector3d> points{{1, 0, 0}, {-1, 0, 0}, {0, 2, 0}, {0, -2, 0}, {0, 0, 3}, {0, 0, -3}};
  core::Trajectory gt, est;
  for (std::size_t k = 0; k < points.size(); ++k) {
    gt.push_back({kStep * static_cast<double>(k), core::SE3::from_translation(points[k])});
    est.push_back({kStep * static_cast<double>(k), core::SE3::from_translation(points[k])});
  }
  constexpr double d = 0.3, n = 6;
  est[2].pose = core::SE3::from_translation({0, 2 + d, 0});
  const auto r = absolute_trajectory_error(gt, est);
  EXPECT_NEAR(r.error.rmse, d * std::sqrt(n - 1) / n, 1e-12);
  EXPECT_NEAR(r.error.max, d * (n - 1) / n, 1e-12);
  EXPECT_NEAR(r.error.min, d / n, 1e-12);
  EXPECT_NEAR(r.error.median, d / n, 1e-12);
  EXPECT_NEAR(r.error.mean, 2 * d * (n - 1) / (n * n), 1e-12);
  EXPECT_NEAR(r.pairs[2].error, d * (n - 1) / n, 1e-12);
  EXPECT_TRUE(r.alignment.rotation_matrix().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
}

core::Trajectory shifted_stamps(core::Trajectory t, double dt) {
  for (auto& p : t) p.timestamp += dt;
  return t;
}

TEST(Ate, AssociationWindowIsStrictAndConfigurable) {
  const auto gt = make(40, helix);
  constexpr double dt = 1.0 / 64;                                                      // 0.015625 s, exact in binary
  EXPECT_EQ(absolute_trajectory_error(gt, shifted_stamps(gt, dt)).pairs.size(), 40u);  // < 0.02 s
  EXPECT_THROW(absolute_trajectory_error(gt, shifted_stamps(gt, dt), {.max_difference = dt}), std::invalid_argument);
  EXPECT_THROW(absolute_trajectory_error(gt, shifted_stamps(gt, 0.03)), std::invalid_argument);  // > 0.02 s
  const auto wide = absolute_trajectory_error(gt, shifted_stamps(gt, 0.03), {.max_difference = 0.04});
  EXPECT_EQ(wide.pairs.size(), 40u);
  EXPECT_NEAR(wide.error.rmse, 0, 1e-12);
  EXPECT_DOUBLE_EQ(wide.pairs[0].est_timestamp - wide.pairs[0].gt_timestamp, 0.03);
  // A clock offset is undone by the offset option.
  EXPECT_EQ(absolute_trajectory_error(gt, shifted_stamps(gt, 100.0), {.offset = -100.0}).pairs.size(), 40u);
}

TEST(Ate, FewerThanThreePairsIsAClearError) {
  const auto gt = make(40, helix);
  const core::Trajectory est(gt.begin(), gt.begin() + 2);
  try {
    absolute_trajectory_error(gt, est);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("at least 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("found 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(absolute_trajectory_error({}, est), std::invalid_argument);
  EXPECT_THROW(absolute_trajectory_error(gt, gt, {.max_difference = 0}), std::invalid_argument);
}

TEST(Ate, RepeatedTimestampIsAnError) {
  auto est = make(10, helix);
  est.push_back(est[3]);
  EXPECT_THROW(absolute_trajectory_error(make(10, helix), est), std::invalid_argument);
}

TEST(Ate, RealGroundTruthAgainstItselfMoved) {
  const std::filesystem::path file = std::filesystem::path(CVO_SHARED_DATA_DIR) / "tum/fr1_rpy/groundtruth.txt";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  const auto gt = io::read_tum_trajectory(file);
  const core::SE3 moved = core::SE3::exp((core::Vector6d() << 0.5, -2, 1, 0.2, 0.1, -1.0).finished());
  const auto r = absolute_trajectory_error(gt, transformed(moved, gt));
  EXPECT_EQ(r.pairs.size(), gt.size());
  EXPECT_LT(r.error.max, 1e-9);
}

}  // namespace
}  // namespace cvo::eval
