#include "libcvo/sim/kinect_depth.hpp"

#include <cmath>
#include <iostream>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/camera.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/random.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"

namespace cvo::sim {
namespace {

KinectDepthOptions kinect(double disparity_sigma_px) {
  KinectDepthOptions options;
  options.enabled = true;
  options.disparity_sigma_px = disparity_sigma_px;
  return options;
}

// The distinct depths the sensor can report between lo and hi, noise off.
std::vector<double> reported_depths(const KinectDepthOptions& options, double lo, double hi) {
  std::set<double> depths;
  for (double z = lo; z <= hi; z += 1e-5) depths.insert(kinect_depth(options, z, 0));
  return {depths.begin(), depths.end()};
}

TEST(KinectDepth, StepsAtOneAndThreeMetresAreZSquaredOverEightFocalBaseline) {
  const KinectDepthOptions options = kinect(0.0);
  EXPECT_NEAR(kinect_depth_step(options, 1.0), 1.0 / (8 * 580.0 * 0.075), 1e-12);  // 2.87 mm
  EXPECT_NEAR(kinect_depth_step(options, 3.0), 9.0 / (8 * 580.0 * 0.075), 1e-12);  // 25.9 mm
  for (const double z : {1.0, 3.0}) {
    const auto depths =
        reported_depths(options, z - 3 * kinect_depth_step(options, z), z + 3 * kinect_depth_step(options, z));
    ASSERT_GE(depths.size(), 5u) << z;
    for (std::size_t i = 1; i < depths.size(); ++i) {
      const double mid = 0.5 * (depths[i] + depths[i - 1]);
      EXPECT_NEAR(depths[i] - depths[i - 1], kinect_depth_step(options, mid), 0.01 * kinect_depth_step(options, mid))
          << "near " << z << " m";
    }
  }
}

TEST(KinectDepth, NoiseIsInDisparitySoItGrowsAsTheSquareOfDepth) {
  const KinectDepthOptions options = kinect(0.07);
  for (const double z : {1.0, 2.0, 3.0, 4.0}) {
    double sum = 0, sum2 = 0;
    constexpr int kN = 20000;
    for (int i = 0; i < kN; ++i) {
      const double e = kinect_depth(options, z, hash(7, i)) - z;
      sum += e;
      sum2 += e * e;
    }
    const double rms = std::sqrt(sum2 / kN);
    // Disparity noise and quantisation add: sigma_d^2 + (1/8)^2 / 12 pixels^2, times (z^2 / f b)^2.
    const double model = z * z / (580.0 * 0.075) * std::sqrt(0.07 * 0.07 + 1.0 / (64.0 * 12.0));
    EXPECT_NEAR(rms, model, 0.1 * model) << z << " m";
    EXPECT_LT(std::abs(sum / kN), 0.1 * model) << z << " m: biased";
  }
}

TEST(KinectDepth, NothingOutsideTheRange) {
  const KinectDepthOptions options = kinect(0.07);
  EXPECT_EQ(kinect_depth(options, 0.45, 1), 0.0);
  EXPECT_EQ(kinect_depth(options, 4.6, 1), 0.0);
  EXPECT_GT(kinect_depth(options, 4.4, 1), 0.0);
  EXPECT_GT(kinect_depth(options, 0.55, 1), 0.0);
}

// A wall 3 m ahead, head on: every reported depth is one of the sensor's lattice depths 8 f b / k
// (within the 16-bit image's 0.2 mm), the same seed gives the same image and another seed another.
TEST(KinectDepth, RenderedWallLiesOnTheDisparityLatticeAndFollowsTheSeed) {
  const Scene wall = make_scene(SceneKind::textured_wall, 0);
  core::Intrinsics k = *core::camera_preset("synthetic");
  const core::SE3 pose = look_at({0.2, -0.5, 1.4}, {0.2, 2.5, 1.4});
  const Radiance radiance = render_radiance(wall, k, [&](int) { return pose; }, {8.0, false});
  const KinectDepthOptions options = kinect(0.07);
  const cv::Mat depth = depth_image(radiance.depth, k, {}, 3, options);
  const double fb8 = 8 * 580.0 * 0.075;
  int valid = 0, off_lattice = 0;
  std::set<std::uint16_t> values;
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const std::uint16_t raw = depth.at<std::uint16_t>(v, u);
      if (raw == 0) continue;
      ++valid;
      values.insert(raw);
      const double z = raw / k.depth_scale, index = fb8 / z;
      const double lattice_z = fb8 / std::round(index);
      off_lattice += std::abs(z - lattice_z) > 0.6 / k.depth_scale;
    }
  std::cout << "wall at 3 m: " << values.size() << " distinct depths, valid " << 100.0 * valid / depth.total() << "%\n";
  EXPECT_GT(valid, static_cast<int>(depth.total()) * 95 / 100);
  EXPECT_EQ(off_lattice, 0);
  EXPECT_GE(values.size(), 2u) << "disparity noise must move some pixels to the next step";
  EXPECT_LE(values.size(), 8u) << "steps of 2.6 cm at 3 m, noise of 1.4 cm: only a few";
  EXPECT_EQ(cv::norm(depth, depth_image(radiance.depth, k, {}, 3, options), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(depth, depth_image(radiance.depth, k, {}, 4, options), cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace cvo::sim
