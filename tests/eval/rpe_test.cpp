#include "libcvo/eval/rpe.hpp"

#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "eval/test_trajectories.hpp"
#include "libcvo/eval/ate.hpp"
#include "libcvo/io/trajectory_io.hpp"

namespace cvo::eval {
namespace {

using testing::helix;
using testing::make;
using testing::rot_z;
using testing::transformed;

// The arccos of the trace cannot resolve angles below ~1e-8 rad: the script's own limit.
constexpr double kAngleTolDeg = 1e-5;

core::SE3 along_x(double x) { return core::SE3::from_translation({x, 0, 0}); }

core::Trajectory at_stamps(const std::vector<double>& stamps, const std::function<core::SE3(double)>& pose) {
  core::Trajectory t;
  for (const double s : stamps) t.push_back({s, pose(s)});
  return t;
}

std::vector<double> stamps_from(double first, double last, double step) {
  std::vector<double> s;
  for (double t = first; t <= last; t += step) s.push_back(t);  // steps exact in binary
  return s;
}

TEST(Rpe, IdenticalTrajectoriesHaveZeroError) {
  const auto gt = make(41, helix);
  const auto r = relative_pose_error(gt, gt);
  EXPECT_EQ(r.pairs.size(), 32u);  // 41 poses 1/8 s apart: i + 8 must not be the last index
  EXPECT_NEAR(r.translation.max, 0, 1e-12);
  EXPECT_NEAR(r.rotation_deg.max, 0, kAngleTolDeg);
}

TEST(Rpe, ConstantRigidOffsetHasZeroError) {
  const auto gt = make(41, helix);
  const auto est = transformed(core::SE3::exp((core::Vector6d() << 4, -2, 1, 0.3, 0.9, -2.2).finished()), gt);
  const auto r = relative_pose_error(gt, est);
  EXPECT_NEAR(r.translation.max, 0, 1e-12);
  EXPECT_NEAR(r.rotation_deg.max, 0, kAngleTolDeg);
}

// Estimate x = (1 + v) t against x = t: every 1 s pair moved (1 + v) m instead of 1 m.
TEST(Rpe, DriftAlongXGivesItsSpeed) {
  constexpr double v = 0.05;
  const auto gt = make(41, along_x);
  const auto est = make(41, [](double t) { return along_x((1 + v) * t); });
  const auto r = relative_pose_error(gt, est);
  EXPECT_EQ(r.pairs.size(), 32u);
  EXPECT_NEAR(r.translation.rmse, v, 1e-12);
  EXPECT_NEAR(r.translation.min, v, 1e-12);
  EXPECT_NEAR(r.translation.max, v, 1e-12);
  EXPECT_NEAR(r.rotation_deg.rmse, 0, kAngleTolDeg);
  EXPECT_DOUBLE_EQ(r.delta, 1.0);

  const auto two = relative_pose_error(gt, est, {.delta = 2.0});
  EXPECT_EQ(two.pairs.size(), 24u);                 // i + 16 <= 39
  EXPECT_NEAR(two.translation.rmse, 2 * v, 1e-12);  // per delta, not divided by it (as the script)
}

TEST(Rpe, ConstantExtraRotationRateGivesItsRate) {
  constexpr double rate_deg = 10.0;
  const auto gt = make(41, along_x);
  const auto est = make(41, [](double t) {
    return core::SE3(rot_z(rate_deg * std::numbers::pi / 180 * t).rotation(), Eigen::Vector3d(t, 0, 0));
  });
  const auto r = relative_pose_error(gt, est);
  EXPECT_NEAR(r.rotation_deg.rmse, rate_deg, kAngleTolDeg);
  EXPECT_NEAR(r.rotation_deg.min, rate_deg, kAngleTolDeg);
  EXPECT_NEAR(r.rotation_deg.max, rate_deg, kAngleTolDeg);
}

// The script's error is ominus(ominus(E_j, E_i), ominus(G_j, G_i)) = A B^-1, A = E_i^-1 E_j and
// B = G_i^-1 G_j, not A^-1 B. Ground truth moves 1 m/s along x without turning; the estimate
// moves the same in the world but turns at w = 90 deg/s. Then A B^-1 has translation
// Rz(-w t_i) e_x - Rz(w) e_x, of norm 2 sin(w (1 + t_i) / 2): sqrt(2) for t_i = 0 (A^-1 B: 0).
TEST(Rpe, ErrorIsTheScriptsOminusOfOminus) {
  constexpr double w = std::numbers::pi / 2;
  const std::vector<double> stamps{0, 0.5, 1, 1.5, 2};
  const auto gt = at_stamps(stamps, along_x);
  const auto est = at_stamps(stamps, [](double t) { return core::SE3(rot_z(w * t).rotation(), {t, 0, 0}); });
  const auto r = relative_pose_error(gt, est);
  ASSERT_EQ(r.pairs.size(), 2u);
  EXPECT_NEAR(r.pairs[0].translation, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(r.pairs[1].translation, 2 * std::sin(w * 1.5 / 2), 1e-12);
  EXPECT_NEAR(r.pairs[0].rotation_deg, 90, kAngleTolDeg);
}

TEST(Rpe, PairEndingOnTheLastPoseIsDropped) {
  const auto gt = at_stamps({0, 1, 2, 3, 4}, along_x);
  const auto r = relative_pose_error(gt, gt);
  ASSERT_EQ(r.pairs.size(), 3u);  // (0,1) (1,2) (2,3); (3,4) ends on the last pose, (4,4) too
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(r.pairs[k].est_timestamp_0, static_cast<double>(k));
    EXPECT_DOUBLE_EQ(r.pairs[k].est_timestamp_1, static_cast<double>(k + 1));
    EXPECT_DOUBLE_EQ(r.pairs[k].gt_timestamp_1, static_cast<double>(k + 1));
  }
}

// Ground truth every 0.5 s with a hole from 3 s to 7 s: median interval 0.5 s, so a pose counts as
// covered up to 1 s from the nearest ground truth. Estimate stamps 4.5, 5 and 5.5 are not covered,
// which removes the pairs starting at 3.5, 4, 4.5, 5 and 5.5: 13 of the 18 pairs remain.
TEST(Rpe, PairsWithoutGroundTruthNearbyAreSkipped) {
  auto gt_stamps = stamps_from(0, 3, 0.5);
  for (const double t : stamps_from(7, 10, 0.5)) gt_stamps.push_back(t);
  const auto still = [](double) { return core::SE3(); };
  const auto r = relative_pose_error(at_stamps(gt_stamps, still), at_stamps(stamps_from(0, 10, 0.5), still));
  ASSERT_EQ(r.pairs.size(), 13u);
  for (const auto& p : r.pairs) EXPECT_TRUE(p.est_timestamp_0 < 3.5 || p.est_timestamp_0 > 5.5) << p.est_timestamp_0;
}

TEST(Rpe, TooShortOrNotOverlappingIsAClearError) {
  const auto gt = make(41, along_x);
  try {
    relative_pose_error(gt, make(5, along_x));  // 0.5 s: every pair ends on the last pose
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("found 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(relative_pose_error(gt, make(41, along_x, 100.0)), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(gt, make(1, along_x)), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(gt, gt, {.delta = 0}), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(gt, gt, {.delta = std::nan("")}), std::invalid_argument);
}

TEST(Rpe, ErrorTransformAndAngleHelpers) {
  const core::SE3 a = core::SE3::exp((core::Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  EXPECT_TRUE(relative_pose_error_transform(a, a, a, a).matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12));
  EXPECT_NEAR(rotation_angle_from_trace(rot_z(2.0)), 2.0, 1e-12);
  EXPECT_NEAR(rotation_angle_from_trace(rot_z(std::numbers::pi)), std::numbers::pi, 1e-7);
}

// Real ground truth against itself drifting at v along world x: rotations agree, so the error of a
// pair is exactly v times its time span; the ATE is below that of a translation-only fit.
TEST(Rpe, RealGroundTruthAgainstItselfDrifting) {
  const std::filesystem::path file = std::filesystem::path(CVO_SHARED_DATA_DIR) / "tum/fr1_rpy/groundtruth.txt";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  const auto gt = io::read_tum_trajectory(file);
  constexpr double v = 0.02;
  auto est = gt;
  for (auto& p : est)
    p.pose = core::SE3(p.pose.rotation(),
                       p.pose.translation() + Eigen::Vector3d(v * (p.timestamp - gt.front().timestamp), 0, 0));
  const auto r = relative_pose_error(gt, est);
  EXPECT_GT(r.pairs.size(), 1000u);
  for (const auto& p : r.pairs) {
    EXPECT_NEAR(p.translation, v * (p.est_timestamp_1 - p.est_timestamp_0), 1e-9);
    EXPECT_NEAR(p.rotation_deg, 0, kAngleTolDeg);
  }
  EXPECT_NEAR(r.translation.rmse, v, 1e-4);  // spans are 1 s to within half a ground-truth interval

  const auto ate = absolute_trajectory_error(gt, est);
  double mean_t = 0, var_t = 0;
  for (const auto& p : gt) mean_t += p.timestamp / static_cast<double>(gt.size());
  for (const auto& p : gt) var_t += (p.timestamp - mean_t) * (p.timestamp - mean_t) / static_cast<double>(gt.size());
  EXPECT_GT(ate.error.rmse, 0.0);
  EXPECT_LE(ate.error.rmse, v * std::sqrt(var_t) + 1e-9);
}

}  // namespace
}  // namespace cvo::eval
