#include "libcvo/sim/exposure.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/camera.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"
#include "libcvo/sim/sensor.hpp"
#include "tests/support/small_camera.hpp"

namespace cvo::sim {
namespace {

// A quarter-size synthetic camera: these tests compare images, not registration.
core::Intrinsics small_camera() { return cvo::testing::small_synthetic_camera(4); }

TEST(MotionBlur, SubExposuresAreTheMidpointsOfEqualSlicesOfTheExposure) {
  EXPECT_EQ(sub_exposure_offsets({}), std::vector<double>{0.0});
  const auto offsets = sub_exposure_offsets({0.01, 5});
  ASSERT_EQ(offsets.size(), 5u);
  for (std::size_t j = 0; j < 5; ++j) EXPECT_NEAR(offsets[j], 0.01 * ((j + 0.5) / 5 - 0.5), 1e-15);
  EXPECT_EQ(offsets[2], 0.0) << "an odd count has the mid-exposure pose";
}

// During a fast turn: the blurred colour is the mean of sharp images at the sub-exposure poses,
// its depth is the mid-exposure one, and it is visibly smoother than the sharp frame; a zero
// exposure gives render()'s frame to the byte.
TEST(MotionBlur, ColourIsTheMeanOfSubExposuresAndZeroExposureIsTheSharpFrame) {
  const Scene scene = make_scene(SceneKind::textured_room, 4);
  const core::Intrinsics k = small_camera();
  const double t = 2.0;
  const auto pose = [&](int, double offset) { return path_pose(PathKind::fast_rpy, t + offset); };
  const ExposureOptions exposure{0.02, 5};
  const Radiance blurred = expose(scene, k, pose, exposure);
  cv::Mat mean;
  for (const double offset : sub_exposure_offsets(exposure)) {
    const cv::Mat sharp = render_radiance(scene, k, [&](int row) { return pose(row, offset); }).bgr;
    mean = mean.empty() ? sharp.clone() : mean + sharp;
  }
  mean /= 5.0;
  EXPECT_LT(cv::norm(blurred.bgr, mean, cv::NORM_INF), 1e-12);
  const Radiance sharp = render_radiance(scene, k, [&](int row) { return pose(row, 0.0); });
  for (std::size_t i = 0; i < sharp.depth.size(); ++i) ASSERT_EQ(blurred.depth[i].z, sharp.depth[i].z) << i;
  const auto roughness = [](const cv::Mat& image) {
    cv::Mat dx;
    cv::absdiff(image.colRange(1, image.cols), image.colRange(0, image.cols - 1), dx);
    const cv::Scalar m = cv::mean(dx);
    return m[0] + m[1] + m[2];
  };
  EXPECT_LT(roughness(blurred.bgr), 0.8 * roughness(sharp.bgr)) << "a 20 ms exposure at 200 deg/s must smear";

  const core::RgbdFrame plain = render(scene, k, path_pose(PathKind::fast_rpy, t));
  const core::RgbdFrame zero = develop(expose(scene, k, pose, {}), k, 1.0, {}, {}, 0);
  EXPECT_EQ(cv::norm(plain.bgr, zero.bgr, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(plain.depth, zero.depth, cv::NORM_INF), 0.0);
}

AutoExposureOptions auto_exposure() {
  AutoExposureOptions options;
  options.enabled = true;
  return options;
}

// Starting converged on a bright view, then looking at a view half as bright: the gain closes
// the log-gain gap by the factor (1 - a) a frame, a = 1 - exp(-1 / (30 Hz x 0.1 s)), so it is
// within 1/e of the gap after three frames (one time constant) and converged after a second.
TEST(AutoExposure, GainFollowsBrightnessWithTheStatedLag) {
  AutoExposure ae(auto_exposure(), 30.0);
  const double a = 1.0 - std::exp(-1.0 / 3.0);
  EXPECT_NEAR(ae.step_fraction(), a, 1e-15);
  EXPECT_DOUBLE_EQ(ae.expose(0.6), 0.45 / 0.6) << "the loop starts converged";
  const double from = std::log(0.45 / 0.6), to = std::log(0.45 / 0.3);
  double gap = from - to;  // the first frame moved towards 0.6's target: no change yet
  for (int n = 1; n <= 30; ++n) {
    const double gain = ae.expose(0.3);
    EXPECT_NEAR(std::log(gain) - to, gap, 1e-12) << "frame " << n;
    gap *= 1.0 - a;
    if (n == 4) {
      EXPECT_NEAR(std::log(gain) - to, (from - to) * std::exp(-1.0), 1e-12) << "one time constant";
    }
  }
  EXPECT_NEAR(ae.expose(0.3), 0.45 / 0.3, 1e-4);
}

TEST(AutoExposure, GainStaysWithinItsLimitsAndIsOneWhenOff) {
  AutoExposure ae(auto_exposure(), 30.0);
  EXPECT_DOUBLE_EQ(ae.target_gain(0.01), 4.0);
  EXPECT_DOUBLE_EQ(ae.target_gain(0.0), 4.0);
  EXPECT_DOUBLE_EQ(ae.target_gain(1.0), 0.45);
  EXPECT_DOUBLE_EQ(ae.target_gain(2.0), 0.25);
  EXPECT_DOUBLE_EQ(ae.expose(0.01), 4.0);
  AutoExposure off({}, 30.0);
  EXPECT_DOUBLE_EQ(off.expose(0.01), 1.0);
  EXPECT_DOUBLE_EQ(off.expose(0.9), 1.0);
}

TEST(AutoExposure, MeanLuminanceWeighsChannelsAndClipsAtOne) {
  const cv::Mat grey(3, 3, CV_64FC3, cv::Scalar::all(0.4));
  EXPECT_NEAR(mean_luminance(grey), 0.4, 1e-12);
  const cv::Mat green(3, 3, CV_64FC3, cv::Scalar(0, 2.0, 0));
  EXPECT_NEAR(mean_luminance(green), 0.587, 1e-12);
}

}  // namespace
}  // namespace cvo::sim
