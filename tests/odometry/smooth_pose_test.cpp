// The published pose of KF-CVO is smooth enough for a controller that differentiates it (issue 25,
// item 7): its error from one frame to the next (the benchmark's RPE over one frame, `cvo-eval
// --delta 0.033`) against frame-to-frame CVO's and OpenCV's RGB-D odometry's on the same frames,
// the real TUM fr1/rpy and a rendered orbit with Kinect-like noise. Figures of every sequence:
// bench/odometry-tuning.md ("A smooth published pose").
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "libcvo/config/module_parameters.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/frame_to_frame.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/opencv_odometry.hpp"
#include "libcvo/sim/sequence.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::odometry {
namespace {

const std::filesystem::path kFr1Rpy = std::filesystem::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy";

// The published poses of every tracked frame of `folder`.
template <typename Odometry>
core::Trajectory track_all(const std::filesystem::path& folder, Odometry&& odometry) {
  auto sequence = io::TumSequence::open(folder);
  core::Trajectory estimate;
  while (const auto frame = sequence.next()) {
    const auto r = odometry.track(*frame);
    if (r.tracked()) estimate.push_back({frame->timestamp, r.published_pose()});
  }
  return estimate;
}

template <typename Odometry, typename Parameters>
core::Trajectory track_all(const std::filesystem::path& folder) {
  const auto K = io::TumSequence::open(folder).intrinsics();
  return track_all(folder, Odometry(K.width, K.height, Parameters{}));
}

// KF-CVO's published pose and OpenCV's RGB-D odometry, as cvo-run runs them, on `folder`.
void expect_no_less_smooth_than_opencv(const std::filesystem::path& folder, const char* name) {
  const config::Config config;
  const auto K = io::TumSequence::open(folder).intrinsics();
  const core::Trajectory gt = io::TumSequence::open(folder).groundtruth();
  const eval::RpeOptions one_frame{.delta = 0.033};
  const auto kf = eval::relative_pose_error(
      gt, track_all(folder, KeyframeOdometry(K.width, K.height, config::keyframe_odometry_parameters(config))),
      one_frame);
  const auto cv = eval::relative_pose_error(
      gt, track_all(folder, OpenCvOdometry(K, config::opencv_odometry_parameters(config, OpenCvVariant::rgbd))),
      one_frame);
  std::printf("%s, one-frame RPE: kf-cvo %.3f mm %.4f deg, opencv-rgbd %.3f mm %.4f deg (%zu pairs)\n", name,
              1e3 * kf.translation.rmse, kf.rotation_deg.rmse, 1e3 * cv.translation.rmse, cv.rotation_deg.rmse,
              kf.pairs.size());
  EXPECT_LE(kf.translation.rmse, cv.translation.rmse);
  EXPECT_LE(kf.rotation_deg.rmse, cv.rotation_deg.rmse);
}

TEST(SmoothPose, KeyframePoseMovesFromFrameToFrameNoWorseThanFrameToFrameCvoOnFr1Rpy) {
  if (!std::filesystem::exists(kFr1Rpy / "rgb.txt")) GTEST_SKIP() << "shared data absent: " << kFr1Rpy;
  const core::Trajectory gt = io::TumSequence::open(kFr1Rpy).groundtruth();
  const eval::RpeOptions one_frame{.delta = 0.033};
  const auto kf =
      eval::relative_pose_error(gt, track_all<KeyframeOdometry, KeyframeOdometryParameters>(kFr1Rpy), one_frame);
  const auto f2f =
      eval::relative_pose_error(gt, track_all<FrameToFrameOdometry, FrameToFrameParameters>(kFr1Rpy), one_frame);
  std::printf("fr1/rpy, one-frame RPE: kf-cvo %.2f mm %.3f deg, cvo %.2f mm %.3f deg (%zu pairs)\n",
              1e3 * kf.translation.rmse, kf.rotation_deg.rmse, 1e3 * f2f.translation.rmse, f2f.rotation_deg.rmse,
              kf.pairs.size());
  EXPECT_LE(kf.translation.rmse, f2f.translation.rmse);
  EXPECT_LE(kf.rotation_deg.rmse, f2f.rotation_deg.rmse);
}

TEST(SmoothPose, PublishedPoseMovesFromFrameToFrameNoMoreThanOpenCvsOnFr1Rpy) {
  if (!std::filesystem::exists(kFr1Rpy / "rgb.txt")) GTEST_SKIP() << "shared data absent: " << kFr1Rpy;
  expect_no_less_smooth_than_opencv(kFr1Rpy, "fr1/rpy");
}

TEST(SmoothPose, PublishedPoseMovesFromFrameToFrameNoMoreThanOpenCvsOnARenderedOrbitWithSensorNoise) {
  cvo::test::TempDir dir;
  sim::SequenceOptions orbit;
  orbit.frames = 90;
  orbit.noise.enabled = true;
  sim::write_sequence(dir.path(), orbit);
  expect_no_less_smooth_than_opencv(dir.path(), "rendered orbit, Kinect-like noise");
}

}  // namespace
}  // namespace cvo::odometry
