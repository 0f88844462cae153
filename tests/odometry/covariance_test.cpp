// The covariances KF-CVO publishes (pose_covariance.hpp, edge_covariance.hpp, variance_factor.hpp):
// their maths on hand-made inputs, and their consistency (NEES) against ground truth.
#include <cstdio>
#include <filesystem>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "libcvo/config/config.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/eval/nees.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/pose_covariance.hpp"
#include "libcvo/odometry/variance_factor.hpp"
#include "tests/odometry/odometry_fixtures.hpp"

namespace cvo::odometry {
namespace {

namespace fs = std::filesystem;

core::Matrix6d spd(double scale, double coupling) {
  core::Matrix6d A = core::Matrix6d::Identity();
  A(0, 4) = A(4, 0) = coupling;
  A(2, 3) = A(3, 2) = -coupling;
  return scale * A;
}

const core::SE3 kMotion{core::so3_exp({0.1, -0.2, 0.3}), Eigen::Vector3d(0.2, -0.1, 0.05)};

TEST(PoseCovariance, TheFirstFrameHasNoRelativeCovarianceAndAZeroOdometryOne) {
  PoseCovarianceChain chain;
  chain.previous_odometry = spd(1, 0);
  const auto c = track_unmeasured(chain, true, true);
  EXPECT_FALSE(c.relative.has_value());
  EXPECT_TRUE(c.odometry.isZero());
}

// Unfused (K_c = 0): the relative pose is (T_m^{n-1})⁻¹ T_m^n, two independent keyframe edges.
TEST(PoseCovariance, WithoutTheChainTheRelativePoseSumsTheTwoKeyframeEdges) {
  PoseCovarianceChain chain;
  chain.previous_fused = spd(2e-6, 0.3);
  chain.keyframe_odometry = spd(1e-4, 0.1);
  const core::Matrix6d kf = spd(1e-6, 0.2);
  const auto c = track_against_keyframe(chain, kMotion, kf, spd(1e6, 0), std::nullopt);
  ASSERT_TRUE(c.relative.has_value());
  EXPECT_LT((*c.relative - left_to_right(kMotion, kf + spd(2e-6, 0.3))).norm(), 1e-15);
  EXPECT_LT((c.odometry - left_to_right(kMotion, spd(1e-4, 0.1) + kf)).norm(), 1e-15);
  EXPECT_LT((chain.previous_fused - kf).norm(), 1e-18) << "the next frame's Σ̄_{n-1}";
}

// Fused with a chain of equal information, the gain is 1/2: half of each error goes through.
TEST(PoseCovariance, FusionWithTheChainSplitsTheErrorByTheFusionsGain) {
  PoseCovarianceChain chain;  // frame n-1 is the keyframe: Σ̄_{n-1} = 0
  const core::Matrix6d kf = spd(1e-6, 0), f2f = spd(1e-6, 0);
  const auto c = track_against_keyframe(chain, core::SE3(), kf, spd(1e6, 0), ChainTerm{f2f, spd(1e6, 0), core::SE3()});
  EXPECT_LT((*c.relative - 0.25 * (kf + f2f)).norm(), 1e-18);
}

// Left, then right: exp(e) T = T exp(Ad(T⁻¹) e).
TEST(PoseCovariance, LeftToRightIsTheAdjointOfTheInverse) {
  const core::Vector6d e = (core::Vector6d() << 1e-4, -2e-4, 3e-4, 1e-4, 2e-4, -1e-4).finished();
  const core::Vector6d right = ((kMotion).inverse() * core::SE3::exp(e) * kMotion).log();
  const core::Matrix6d sigma = e * e.transpose();
  EXPECT_LT((left_to_right(kMotion, sigma) - right * right.transpose()).norm(), 1e-12);
}

// When the back end agrees with the odometry about keyframe k, the map pose is as uncertain as the
// odometry pose; a more certain keyframe makes it more certain.
TEST(PoseCovariance, TheMapPoseComposesTheKeyframesMapCovarianceWithTheOdometrySince) {
  const core::Matrix6d at_k = spd(1e-4, 0.2);
  const core::Matrix6d at_n = left_to_right(kMotion, at_k) + spd(1e-5, 0.1);
  EXPECT_LT((map_pose_covariance(at_k, at_k, at_n, kMotion) - at_n).norm(), 1e-12);
  const core::Matrix6d certain = map_pose_covariance(spd(1e-6, 0), at_k, at_n, kMotion);
  EXPECT_LT((certain - (left_to_right(kMotion, spd(1e-6, 0)) + spd(1e-5, 0.1))).norm(), 1e-12);
  // An odometry covariance below the keyframe's (a frame tracked against an earlier keyframe)
  // never makes it indefinite.
  const Eigen::SelfAdjointEigenSolver<core::Matrix6d> eig(map_pose_covariance(at_k, at_n, at_k, core::SE3()));
  EXPECT_GE(eig.eigenvalues().minCoeff(), 0);
}

TEST(VarianceFactor, StartsAtOneAndLearnsTheRatioOfTheDisagreementsChiSquareToSix) {
  VarianceFactor factor;
  EXPECT_DOUBLE_EQ(factor.value(), 1.0);
  for (int k = 0; k < 2000; ++k) add_disagreement(factor, 24.0);
  EXPECT_NEAR(factor.value(), 4.0, 0.05);
  add_disagreement(factor, 1e12);  // a gross disagreement counts capped
  EXPECT_LT(factor.value(), 4.5);
  EXPECT_NEAR(disagreement_chi2(core::Vector6d::Ones(), 2 * core::Matrix6d::Identity()), 3.0, 1e-12);
  EXPECT_LT(disagreement_chi2(core::Vector6d::Ones(), -core::Matrix6d::Identity()), 0);
}

// Runs KF-CVO over frames with ground truth and returns the NEES of its relative poses.
eval::NeesResult nees_of_run(const std::vector<core::RgbdFrame>& frames, const core::Trajectory& truth,
                             const core::Intrinsics& camera) {
  KeyframeOdometry tracker(camera.width, camera.height, config::keyframe_odometry_parameters(config::Config{}));
  core::Trajectory estimate;
  std::vector<io::StampedCovariance> covariances;
  for (const auto& frame : frames) {
    const TrackStep step = tracker.track(frame);
    estimate.push_back({frame.timestamp, step.pose});
    if (step.relative_covariance) covariances.push_back({frame.timestamp, *step.relative_covariance});
    EXPECT_TRUE(step.odometry_covariance.allFinite());
  }
  EXPECT_GE(covariances.size() + 2, frames.size()) << "every tracked frame but the first has one";
  return eval::relative_pose_nees(truth, estimate, covariances);
}

void expect_consistent_on_rendered(sim::PathKind path, std::uint64_t seed) {
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, seed);
  const auto camera = *core::camera_preset("synthetic");
  sim::NoiseOptions noise;
  noise.enabled = true;  // Kinect-like
  const core::Trajectory truth = sim::sample_path(path, 45);
  std::vector<core::RgbdFrame> frames;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    auto frame = sim::render(scene, camera, truth[i].pose, noise, seed + i, testing::fast_render());
    frame.index = i;
    frame.timestamp = frame.depth_timestamp = truth[i].timestamp;
    frames.push_back(std::move(frame));
  }
  const auto r = nees_of_run(frames, truth, camera);
  std::printf("%s: NEES mean %.2f (translation %.2f, rotation %.2f) over %zu pairs\n",
              std::string(sim::path_name(path)).c_str(), r.nees.mean, r.translation.mean, r.rotation.mean,
              r.pairs.size());
  EXPECT_GE(r.nees.mean, 3.0);
  EXPECT_LE(r.nees.mean, 12.0);
}

TEST(KfCvoCovariance, IsConsistentOnARenderedOrbitWithKinectNoise) {
  expect_consistent_on_rendered(sim::PathKind::orbit, 1);
}

TEST(KfCvoCovariance, IsConsistentOnRenderedFastTurnsWithKinectNoise) {
  expect_consistent_on_rendered(sim::PathKind::rpy, 3);
}

// The target on real data. It does not hold yet (bench/odometry-tuning.md, "Covariance":
// per-frame errors of the real sensor that both registrations of a frame share); enable it when
// it does.
TEST(KfCvoCovariance, DISABLED_IsConsistentOnFr1Rpy) {
  const fs::path folder = fs::path(CVO_SHARED_DATA_DIR) / "tum/fr1_rpy";
  if (!fs::exists(folder / "rgb.txt")) GTEST_SKIP() << folder << " is absent (../shared/data)";
  io::TumOptions options;
  options.max_frames = 200;
  auto sequence = io::TumSequence::open(folder, options);
  std::vector<core::RgbdFrame> frames;
  while (auto frame = sequence.next()) frames.push_back(*frame);
  const auto r = nees_of_run(frames, sequence.groundtruth(), sequence.intrinsics());
  std::printf("fr1/rpy: NEES mean %.2f over %zu pairs\n", r.nees.mean, r.pairs.size());
  EXPECT_GE(r.nees.mean, 3.0);
  EXPECT_LE(r.nees.mean, 12.0);
}

}  // namespace
}  // namespace cvo::odometry
