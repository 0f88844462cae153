// The published pose of KF-CVO is smooth enough for a controller that differentiates it: its
// error from one frame to the next (the benchmark's RPE over one frame, `cvo-eval --delta 0.033`)
// on the real TUM fr1/rpy, against frame-to-frame CVO's on the same frames. Figures, and OpenCV's
// odometry on the same run: libcvo/odometry/README.md ("A smooth pose").
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/frame_to_frame.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"

namespace cvo::odometry {
namespace {

const std::filesystem::path kFr1Rpy = std::filesystem::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy";

template <typename Odometry, typename Parameters>
core::Trajectory track_all(const std::filesystem::path& folder) {
  auto sequence = io::TumSequence::open(folder);
  Odometry odometry(sequence.intrinsics().width, sequence.intrinsics().height, Parameters{});
  core::Trajectory estimate;
  while (const auto frame = sequence.next()) {
    const auto r = odometry.track(*frame);
    if (r.tracked()) estimate.push_back({frame->timestamp, r.pose});
  }
  return estimate;
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

}  // namespace
}  // namespace cvo::odometry
