#include "libcvo/sim/render.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "libcvo/core/camera.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/scene.hpp"
#include "tests/support/small_camera.hpp"

namespace cvo::sim {
namespace {

core::Intrinsics synthetic() { return *core::camera_preset("synthetic"); }

// A quarter-size camera for tests that only need image statistics.
core::Intrinsics small_camera() { return cvo::testing::small_synthetic_camera(4); }

PathKind default_path(SceneKind kind) { return kind == SceneKind::textured_wall ? PathKind::wall : PathKind::orbit; }

// Largest distance from any back-projected valid depth pixel to the scene; counts valid pixels.
double max_backprojection_error(const Scene& scene, const core::RgbdFrame& frame, const core::SE3& pose, int& valid) {
  const core::Intrinsics& k = frame.intrinsics;
  double worst = 0;
  for (int v = 0; v < frame.depth.rows; ++v)
    for (int u = 0; u < frame.depth.cols; ++u) {
      const std::uint16_t raw = frame.depth.at<std::uint16_t>(v, u);
      if (raw == 0) continue;
      ++valid;
      const double z = raw / k.depth_scale;
      const Eigen::Vector3d p_cam((u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z);
      worst = std::max(worst, distance_to_surface(scene, pose * p_cam));
    }
  return worst;
}

// The acceptance criterion: every valid depth pixel, back-projected with the ground-truth pose,
// lies within 1 mm of the scene (quantisation allows ~0.1 mm).
TEST(RenderBackProjection, EveryPixelWithinOneMillimetreOfTheScene) {
  double overall = 0;
  for (const auto& name : scene_names()) {
    const SceneKind kind = *parse_scene_kind(name);
    const Scene scene = make_scene(kind, 3);
    const PathKind path = default_path(kind);
    for (const double t : {0.0, 0.37 * path_period(path), 0.71 * path_period(path)}) {
      const core::SE3 pose = path_pose(path, t);
      const std::clock_t start = std::clock();  // CPU time: the build machine may be busy
      const core::RgbdFrame frame = render(scene, synthetic(), pose);
      const double ms = 1000.0 * static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
      int valid = 0;
      const double worst = max_backprojection_error(scene, frame, pose, valid);
      EXPECT_LT(worst, 1e-3) << name << " t=" << t;
      EXPECT_GT(valid, 640 * 480 * 95 / 100) << name << " t=" << t << ": too little valid depth";
      overall = std::max(overall, worst);
      std::cout << name << " t=" << t << ": render " << ms << " ms CPU, max error " << worst * 1e3 << " mm\n";
    }
  }
  RecordProperty("max_backprojection_error_um", static_cast<int>(std::ceil(overall * 1e6)));
}

TEST(RenderBackProjection, ColourAndDepthMatchTheRequestedCamera) {
  const core::RgbdFrame frame =
      render(make_scene(SceneKind::textured_room, 0), small_camera(), path_pose(PathKind::sweep, 0));
  EXPECT_EQ(frame.bgr.type(), CV_8UC3);
  EXPECT_EQ(frame.depth.type(), CV_16UC1);
  EXPECT_EQ(frame.bgr.size(), cv::Size(160, 120));
  EXPECT_EQ(frame.depth.size(), cv::Size(160, 120));
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(RenderDeterminism, SameSeedSameImagesOtherSeedOtherTexture) {
  const core::SE3 pose = path_pose(PathKind::orbit, 1.0);
  NoiseOptions noise;
  noise.enabled = true;
  const auto a = render(make_scene(SceneKind::textured_room, 11), small_camera(), pose, noise, 5);
  const auto b = render(make_scene(SceneKind::textured_room, 11), small_camera(), pose, noise, 5);
  EXPECT_TRUE(identical(a.bgr, b.bgr));
  EXPECT_TRUE(identical(a.depth, b.depth));

  const auto other_texture = render(make_scene(SceneKind::textured_room, 12), small_camera(), pose, noise, 5);
  cv::Mat diff;
  cv::absdiff(a.bgr, other_texture.bgr, diff);
  EXPECT_GT(cv::mean(diff)[0] + cv::mean(diff)[1] + cv::mean(diff)[2], 30.0) << "texture hardly changed";
  EXPECT_TRUE(identical(a.depth, other_texture.depth)) << "the texture seed must not move geometry or noise";

  const auto other_noise = render(make_scene(SceneKind::textured_room, 11), small_camera(), pose, noise, 6);
  EXPECT_TRUE(identical(a.bgr, other_noise.bgr));
  EXPECT_FALSE(identical(a.depth, other_noise.depth));
}

// Gradient magnitude of the grey image by central differences, in grey levels per pixel.
cv::Mat gradient_magnitude(const cv::Mat& bgr) {
  cv::Mat grey, gx, gy, mag;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(grey, CV_32F);
  const cv::Mat kx = (cv::Mat_<float>(1, 3) << -0.5f, 0.f, 0.5f);
  cv::filter2D(grey, gx, CV_32F, kx);
  cv::filter2D(grey, gy, CV_32F, kx.t());
  cv::magnitude(gx, gy, mag);
  return mag;
}

// Surface index per pixel (-1: nothing), by the renderer's own centre rays.
cv::Mat surface_labels(const Scene& scene, const core::Intrinsics& k, const core::SE3& pose) {
  cv::Mat labels(k.height, k.width, CV_32F);  // float: what erode/dilate take
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d d = pose.rotation_matrix() * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      const auto hit = intersect(scene, {pose.translation(), d});
      labels.at<float>(v, u) = hit ? static_cast<float>(hit->surface) : -1.f;
    }
  return labels;
}

// Textured scenes: every 32x32 block has real gradient. Textureless: inside faces (5x5
// neighbourhood on one surface) the image is nearly constant.
TEST(RenderTexture, TexturedHasGradientEverywhereTexturelessOnlyAtEdges) {
  const core::Intrinsics k = synthetic();
  for (const auto& name : scene_names()) {
    const SceneKind kind = *parse_scene_kind(name);
    const Scene scene = make_scene(kind, 21);
    for (const double t : {0.0, 0.5 * path_period(default_path(kind))}) {
      const core::SE3 pose = path_pose(default_path(kind), t);
      const cv::Mat mag = gradient_magnitude(render(scene, k, pose).bgr);
      if (is_textured(kind)) {
        constexpr int kBlock = 32;
        int blocks = 0, weak = 0;
        double weakest = 1e9;
        for (int v = 0; v + kBlock <= k.height; v += kBlock)
          for (int u = 0; u + kBlock <= k.width; u += kBlock) {
            const double m = cv::mean(mag(cv::Rect(u, v, kBlock, kBlock)))[0];
            ++blocks;
            weakest = std::min(weakest, m);
            if (m < 2.0) ++weak;
          }
        std::cout << name << " t=" << t << ": weakest 32x32 block mean gradient " << weakest << ", mean "
                  << cv::mean(mag)[0] << "\n";
        EXPECT_EQ(weak, 0) << name << " t=" << t << ": " << weak << " of " << blocks << " blocks have little gradient";
        EXPECT_GT(cv::mean(mag)[0], 5.0) << name;
      } else {
        const cv::Mat labels = surface_labels(scene, k, pose);
        cv::Mat lo, hi;
        const cv::Mat box = cv::Mat::ones(5, 5, CV_8U);
        cv::erode(labels, lo, box);
        cv::dilate(labels, hi, box);
        const cv::Mat interior = (lo == hi) & (labels >= 0);
        const int n = cv::countNonZero(interior);
        const cv::Mat strong = (mag > 1.0) & interior;
        const double mean_interior = cv::mean(mag, interior)[0];
        std::cout << name << " t=" << t << ": interior mean gradient " << mean_interior << ", "
                  << cv::countNonZero(strong) << " of " << n << " interior pixels above 1 level\n";
        EXPECT_GT(n, k.width * k.height / 2);
        EXPECT_LT(mean_interior, 0.5);
        EXPECT_LT(cv::countNonZero(strong), n / 100);
      }
    }
  }
}

// Head-on at a wall exactly 2 m away: the depth error has the model's std and no bias, and some
// depth goes missing; in the room grazing faces and occlusion edges lose more.
TEST(RenderNoise, MatchesTheAxialModelAndDropsDepth) {
  const Scene wall = make_scene(SceneKind::textured_wall, 0);
  const core::SE3 pose = look_at({0.2, 0.5, 1.4}, {0.2, 2.5, 1.4});
  NoiseOptions noise;
  noise.enabled = true;
  const core::Intrinsics k = synthetic();
  const auto clean = render(wall, k, pose, {}, 0, {8.0, false});
  const auto noisy = render(wall, k, pose, noise, 77, {8.0, false});
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const double c = clean.depth.at<std::uint16_t>(v, u), d = noisy.depth.at<std::uint16_t>(v, u);
      ASSERT_EQ(c, 10000.0);  // 2 m head-on
      if (d == 0) continue;
      const double e = (d - c) / k.depth_scale;
      sum += e;
      sum2 += e * e;
      ++n;
    }
  const double mean = sum / n, std = std::sqrt(sum2 / n - mean * mean);
  std::cout << "wall at 2 m: noise std " << std * 1e3 << " mm (model " << axial_noise_sigma(2.0) * 1e3 << " mm), bias "
            << mean * 1e3 << " mm, valid " << 100.0 * n / (k.width * k.height) << "%\n";
  EXPECT_NEAR(std, axial_noise_sigma(2.0), 0.05 * axial_noise_sigma(2.0));
  EXPECT_NEAR(mean, 0.0, 0.1e-3);
  EXPECT_LT(n, k.width * k.height * 995 / 1000);  // dropout
  EXPECT_GT(n, k.width * k.height * 97 / 100);

  const Scene room = make_scene(SceneKind::textured_room, 0);
  const core::SE3 in_room = path_pose(PathKind::sweep, 3.0);
  const double clean_valid = cv::countNonZero(render(room, k, in_room, {}, 0, {8.0, false}).depth);
  const double noisy_valid = cv::countNonZero(render(room, k, in_room, noise, 1, {8.0, false}).depth);
  std::cout << "room: valid depth " << 100 * clean_valid / (k.width * k.height) << "% clean, "
            << 100 * noisy_valid / (k.width * k.height) << "% noisy\n";
  EXPECT_LT(noisy_valid, clean_valid - 0.02 * k.width * k.height);
}

TEST(RenderNoise, ModelValues) {
  EXPECT_DOUBLE_EQ(axial_noise_sigma(0.4), 0.0012);
  EXPECT_NEAR(axial_noise_sigma(2.0), 0.0012 + 0.0019 * 2.56, 1e-15);
}

}  // namespace
}  // namespace cvo::sim
