#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "libcvo/core/camera.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/colour_noise.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"
#include "libcvo/sim/texture.hpp"

namespace cvo::sim {
namespace {

TEST(WhiteRoom, EverySurfaceIsWhiteWithSmallDifferences) {
  const Scene scene = make_scene(SceneKind::white_room, 3);
  EXPECT_EQ(scene.surfaces.size(), 6u + 7u * 5u);  // room, the five boxes moved out, two more
  for (const auto& surface : scene.surfaces) {
    const Eigen::Vector3d rgb = albedo(surface.texture, 0.3, 0.7);
    EXPECT_EQ(rgb, albedo(surface.texture, 2.1, 0.05)) << "no texture";
    EXPECT_GE(rgb.minCoeff(), 0.84);
    EXPECT_LE(rgb.maxCoeff(), 0.96);
    EXPECT_LE(rgb.maxCoeff() - rgb.minCoeff(), 0.02) << "white, not tinted";
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d corner = surface.quad.origin + (c & 1) * surface.quad.length_s * surface.quad.axis_s +
                                     (c >> 1) * surface.quad.length_t * surface.quad.axis_t;
      EXPECT_LT(room_bounds(SceneKind::white_room).exteriorDistance(corner), 1e-12);
    }
  }
  EXPECT_FALSE(is_textured(SceneKind::white_room));
}

// Along the paths used with it, the walls the camera sees are 3-4 m away (the median depth of the
// pixels on the room's walls, the first six surfaces' vertical ones), where Kinect depth steps are
// centimetres; and nothing is nearer than 0.5 m.
TEST(WhiteRoom, WallsAreThreeToFourMetresFromThePaths) {
  const Scene scene = make_scene(SceneKind::white_room, 0);
  const core::Intrinsics k = *core::camera_preset("synthetic");
  for (const PathKind path : {PathKind::orbit, PathKind::rpy, PathKind::fast_rpy}) {
    for (int i = 0; i < 6; ++i) {
      const core::SE3 pose = path_pose(path, path_period(path) * i / 6.0);
      EXPECT_GT(distance_to_surface(scene, pose.translation()), 0.5);
      std::vector<double> z;
      for (int v = 0; v < k.height; v += 8)
        for (int u = 0; u < k.width; u += 8) {
          const Eigen::Vector3d d = pose.rotation_matrix() * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1);
          const auto hit = intersect(scene, {pose.translation(), d});
          if (hit && hit->surface < 6 && std::abs(hit->normal.z()) < 0.5) z.push_back(hit->t);
        }
      ASSERT_FALSE(z.empty()) << path_name(path) << " view " << i << " sees no wall";
      std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
      const double median = z[z.size() / 2];
      EXPECT_GE(median, 2.7) << path_name(path) << " view " << i;
      EXPECT_LE(median, 4.2) << path_name(path) << " view " << i;
    }
  }
}

// Inside one surface the exact rendering varies by shading only (under a level); with the
// camera's colour noise each pixel differs from its neighbours by the noise model's sigma: the
// spread of colours is small and noise-driven.
TEST(WhiteRoom, ColourSpreadIsSmallAndNoiseDriven) {
  const Scene scene = make_scene(SceneKind::white_room, 0);
  const core::Intrinsics k = *core::camera_preset("synthetic");
  const core::SE3 pose = path_pose(PathKind::orbit, 1.0);
  const Radiance radiance = render_radiance(scene, k, [&](int) { return pose; }, {8.0, false});
  ColourNoiseOptions noise;
  noise.enabled = true;
  const cv::Mat clean = develop_colour(radiance.bgr, 1.0, {}, 0), noisy = develop_colour(radiance.bgr, 1.0, noise, 9);
  // The horizontal difference of the green channel between neighbours on the same surface.
  double clean2 = 0, noisy2 = 0, model2 = 0;
  int n = 0;
  for (int v = 0; v < k.height; ++v)
    for (int u = 1; u < k.width; ++u) {
      const auto i = static_cast<std::size_t>(v * k.width + u);
      if (radiance.depth[i].surface < 0 || radiance.depth[i].surface != radiance.depth[i - 1].surface) continue;
      const double c = clean.at<cv::Vec3b>(v, u)[1] - clean.at<cv::Vec3b>(v, u - 1)[1];
      const double d = noisy.at<cv::Vec3b>(v, u)[1] - noisy.at<cv::Vec3b>(v, u - 1)[1];
      clean2 += c * c;
      noisy2 += d * d;
      const double sigma = colour_noise_sigma(noise, clean.at<cv::Vec3b>(v, u)[1]);
      model2 += 2 * sigma * sigma;
      ++n;
    }
  const double clean_rms = std::sqrt(clean2 / n), noisy_rms = std::sqrt(noisy2 / n), model_rms = std::sqrt(model2 / n);
  std::cout << "white room, neighbour differences (green, levels): exact " << clean_rms << ", with noise " << noisy_rms
            << " (model " << model_rms << ")\n";
  EXPECT_LT(clean_rms, 0.5) << "without noise a white surface is nearly one level";
  EXPECT_NEAR(noisy_rms, model_rms, 0.05 * model_rms);
  cv::Mat grey;
  cv::cvtColor(noisy, grey, cv::COLOR_BGR2GRAY);
  cv::Scalar mean, std;
  cv::meanStdDev(grey, mean, std);
  std::cout << "grey level " << mean[0] << " +- " << std[0] << "\n";
  EXPECT_LT(std[0], 25.0) << "every colour alike";
}

}  // namespace
}  // namespace cvo::sim
