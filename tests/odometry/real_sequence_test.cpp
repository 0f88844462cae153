// FrameToFrameOdometry on the committed real sample (TUM fr1/rpy, frames 0-49), evaluated with
// the benchmark's RPE exactly as published numbers are.
#include <cstdio>

#include <gtest/gtest.h>

#include "libcvo/eval/ate.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/frame_to_frame.hpp"

namespace cvo::odometry {
namespace {

TEST(OdometryRealData, Fr1Rpy50RelativePoseError) {
  auto sequence = io::TumSequence::open(CVO_TEST_DATA_DIR "/fr1_rpy_50");
  ASSERT_EQ(sequence.size(), 50u);
  FrameToFrameOdometry odometry(sequence.intrinsics().width, sequence.intrinsics().height, {});
  core::Trajectory estimate;
  while (const auto frame = sequence.next()) {
    const TrackResult r = odometry.track(*frame);
    EXPECT_TRUE(r.tracked()) << "frame " << frame->index << ": " << to_string(r.status);
    estimate.push_back({frame->timestamp, r.pose});
  }
  const auto rpe = eval::relative_pose_error(sequence.groundtruth(), estimate);
  const auto ate = eval::absolute_trajectory_error(sequence.groundtruth(), estimate);
  std::printf("fr1_rpy_50: RPE %.4f m/s, %.3f deg/s over %zu pairs (max %.4f m, %.3f deg); ATE %.4f m\n",
              rpe.translation.rmse, rpe.rotation_deg.rmse, rpe.pairs.size(), rpe.translation.max, rpe.rotation_deg.max,
              ate.error.rmse);
  // 50 frames at 30 Hz give only 19 pairs 1 s apart, all overlapping (frames 0-18 to 30-48), so
  // this is one 1.6 s stretch rather than an average. Measured: 0.048 m/s and 2.30 deg/s (the
  // first 200 frames give 0.05-0.065 m/s and 2.4-2.9 deg/s, the paper 0.0457 / 3.31 on the whole
  // sequence). Bounds at ~1.7x, so a regression in selection, registration or the
  // constant-velocity guess shows while the noise of 19 correlated pairs does not.
  EXPECT_EQ(rpe.pairs.size(), 19u);
  EXPECT_LT(rpe.translation.rmse, 0.08);
  EXPECT_LT(rpe.rotation_deg.rmse, 4.0);
  EXPECT_LT(ate.error.rmse, 0.04);
}

}  // namespace
}  // namespace cvo::odometry
