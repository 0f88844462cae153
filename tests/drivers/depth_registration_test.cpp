// Depth registration for cameras whose depth is a separate sensor, checked against the exact depth
// the renderer gives for the colour camera itself.
#include "drivers/depth_registration.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "libcvo/core/units.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"
#include "program/allocation_counter.hpp"

namespace cvo::drivers {
namespace {

// A RealSense D435-like pair: 640x480 colour (69 deg wide), 848x480 depth (87 deg wide, so coarser
// per degree than colour), 1 mm depth units, the depth sensor 15 mm to the side and turned 1 deg.
core::Intrinsics colour_camera() { return {615.0, 615.0, 319.5, 239.5, 640, 480, 1000.0, {}}; }
core::DepthSensor depth_sensor() {
  return {{425.0, 425.0, 423.5, 239.5, 848, 480, 1000.0, {}},
          core::SE3::from_rotation_vector({0, core::radians(1.0), 0}) * core::SE3::from_translation({-0.015, 0, 0})};
}

struct Comparison {
  double covered = 0;     // share of the exact depth's pixels that registration filled
  double within_1pc = 0;  // share of those filled within 1 % of the exact depth
  double far_behind = 0;  // share filled more than 5 % behind the exact depth (an occlusion missed)
};

Comparison compare(const cv::Mat& registered, const cv::Mat& exact) {
  std::size_t truth = 0, filled = 0, close = 0, behind = 0;
  for (int v = 0; v < exact.rows; ++v)
    for (int u = 0; u < exact.cols; ++u) {
      const double z = exact.at<std::uint16_t>(v, u), r = registered.at<std::uint16_t>(v, u);
      if (z == 0) continue;
      ++truth;
      if (r == 0) continue;
      ++filled;
      close += std::abs(r - z) <= 0.01 * z;
      behind += r > 1.05 * z;
    }
  const auto share = [](std::size_t n, std::size_t of) {
    return of ? static_cast<double>(n) / static_cast<double>(of) : 0.0;
  };
  return {share(filled, truth), share(close, filled), share(behind, filled)};
}

TEST(DepthRegistration, TheSameCameraAtTheSamePlaceGivesTheDepthBack) {
  const core::Intrinsics k = colour_camera();
  cv::Mat depth(k.height, k.width, CV_16UC1);
  cv::randu(depth, 500, 4000);
  depth(cv::Rect(100, 100, 50, 50)).setTo(0);  // unmeasured stays unmeasured
  cv::Mat registered;
  DepthRegistration({k, core::SE3()}, k).apply(depth, registered);
  EXPECT_EQ(cv::norm(registered, depth, cv::NORM_INF), 0);
}

TEST(DepthRegistration, ARenderedD435PairMatchesTheColourCamerasExactDepth) {
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 7);
  for (const double t : {0.0, 3.0, 7.5}) {
    const core::SE3 pose = sim::path_pose(sim::PathKind::orbit, t);
    const core::RgbdFrame raw = sim::render_separate_depth(scene, colour_camera(), depth_sensor(), pose);
    ASSERT_EQ(raw.depth.cols, 848);
    const cv::Mat exact = sim::render(scene, colour_camera(), pose).depth;
    cv::Mat registered;
    DepthRegistration(depth_sensor(), colour_camera()).apply(raw.depth, registered);
    const Comparison c = compare(registered, exact);
    std::printf("t = %.1f s: %.1f %% of the exact depth covered, %.2f %% of it within 1 %%, %.3f %% behind by > 5 %%\n",
                t, 100 * c.covered, 100 * c.within_1pc, 100 * c.far_behind);
    EXPECT_GT(c.covered, 0.98) << "at t = " << t;  // all but the strip the depth sensor cannot see
    EXPECT_GT(c.within_1pc, 0.99) << "at t = " << t;
    EXPECT_LT(c.far_behind, 0.002) << "at t = " << t;
    // Unregistered, the same depth is far off: the test measures the registration.
    cv::Mat resized;
    cv::resize(raw.depth, resized, exact.size(), 0, 0, cv::INTER_NEAREST);
    EXPECT_LT(compare(resized, exact).within_1pc, 0.6) << "at t = " << t;
  }
}

TEST(DepthRegistration, TheNearerSurfaceWinsWhereTwoLandOnOnePixel) {
  // A wall 3 m away and, in front of it, a strip 1 m away; the sensor 10 cm to the side of the
  // colour camera sees wall points that, moved to colour, fall behind the strip.
  core::Intrinsics k{300.0, 300.0, 79.5, 59.5, 160, 120, 1000.0, {}};
  cv::Mat depth(k.height, k.width, CV_16UC1, cv::Scalar(3000));
  depth(cv::Rect(70, 0, 20, k.height)).setTo(1000);
  cv::Mat registered;
  DepthRegistration({k, core::SE3::from_translation({0.1, 0, 0})}, k).apply(depth, registered);
  int strip = 0;
  for (int u = 0; u < k.width; ++u) strip += registered.at<std::uint16_t>(60, u) == 1000;
  EXPECT_GE(strip, 19);  // the strip keeps its width ...
  for (int u = 100; u < 118; ++u)
    EXPECT_EQ(registered.at<std::uint16_t>(60, u), 1000) << u;  // ... and is not overdrawn
}

TEST(DepthRegistration, AllocatesNothingOnceItsOutputHasTheColourSize) {
  const DepthRegistration registration(depth_sensor(), colour_camera());
  cv::Mat depth(480, 848, CV_16UC1, cv::Scalar(2000)), registered;
  registration.apply(depth, registered);
  const auto before = program::process_allocations();
  for (int k = 0; k < 3; ++k) registration.apply(depth, registered);
  EXPECT_EQ(program::process_allocations() - before, 0);
}

TEST(DepthRegistration, ADepthImageOfAnotherSizeIsRefused) {
  const DepthRegistration registration(depth_sensor(), colour_camera());
  cv::Mat registered;
  EXPECT_THROW(registration.apply(cv::Mat(480, 640, CV_16UC1, cv::Scalar(1)), registered), std::invalid_argument);
  EXPECT_THROW(DepthRegistration({core::Intrinsics{}, core::SE3()}, colour_camera()), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::drivers
