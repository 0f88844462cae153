// Keypoints with depth: back-projection against the renderer's exact scene, the depth range, and
// the checks on the frame.
#include "libcvo/loop_closure/keypoints_3d.hpp"

#include <cstddef>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"

namespace cvo::loop_closure {
namespace {

struct RenderedFrame {
  sim::Scene scene = sim::make_scene(sim::SceneKind::textured_room, 3);
  core::SE3 pose = sim::path_pose(sim::PathKind::orbit, 2.0);
  core::RgbdFrame frame;
  RenderedFrame() {
    sim::RenderOptions options;
    options.supersample = false;
    const core::Intrinsics camera{525.0, 525.0, 319.5, 239.5, 640, 480, 5000.0};
    frame = sim::render(scene, camera, pose, {}, 0, options);
    frame.intrinsics = camera;
  }
};

TEST(LoopKeypoints3d, RenderedKeypointsLieOnTheSceneSurfaces) {
  const RenderedFrame r;
  const OrbFeatures features = extract_orb(r.frame.bgr);
  const Keypoints3d k = keypoints_with_depth(features, r.frame, 0.1, 8.0);
  ASSERT_GT(k.points.size(), 300u);
  ASSERT_EQ(static_cast<std::size_t>(k.descriptors.rows), k.points.size());
  std::size_t close = 0;
  for (const auto& p : k.points) {
    const double d = sim::distance_to_surface(r.scene, r.pose * p);
    EXPECT_LT(d, 0.02);  // a keypoint on a depth edge may take the other side's depth half a pixel off
    close += d < 0.003 ? 1 : 0;
  }
  // Exact depth (0.1 mm quantisation): nearly every point is on a surface to a few mm.
  EXPECT_GT(static_cast<double>(close), 0.95 * static_cast<double>(k.points.size()));

  // Each descriptor row is the one of its keypoint: the first kept point's row is found in the input.
  bool found = false;
  for (int row = 0; row < features.descriptors.rows && !found; ++row)
    found = cv::norm(features.descriptors.row(row), k.descriptors.row(0), cv::NORM_HAMMING) == 0;
  EXPECT_TRUE(found);
}

TEST(LoopKeypoints3d, KeepsOnlyTheDepthRange) {
  const RenderedFrame r;
  const OrbFeatures features = extract_orb(r.frame.bgr);
  const Keypoints3d all = keypoints_with_depth(features, r.frame, 0.1, 8.0);
  const Keypoints3d near = keypoints_with_depth(features, r.frame, 0.1, 2.0);
  EXPECT_LT(near.points.size(), all.points.size());
  for (const auto& p : near.points) EXPECT_LE(p.z(), 2.0);
  EXPECT_TRUE(keypoints_with_depth(features, r.frame, 9.0, 10.0).points.empty());
  EXPECT_EQ(keypoints_with_depth(features, r.frame, 9.0, 10.0).descriptors.cols, 32);
}

TEST(LoopKeypoints3d, RejectsAFrameWithoutMatchingDepthOrIntrinsics) {
  RenderedFrame r;
  const OrbFeatures features = extract_orb(r.frame.bgr);
  core::RgbdFrame no_depth = r.frame;
  no_depth.depth = cv::Mat();
  EXPECT_THROW(keypoints_with_depth(features, no_depth, 0.1, 8.0), std::invalid_argument);
  core::RgbdFrame bad_camera = r.frame;
  bad_camera.intrinsics.fx = 0;
  EXPECT_THROW(keypoints_with_depth(features, bad_camera, 0.1, 8.0), std::invalid_argument);
  OrbFeatures short_descriptors = features;
  short_descriptors.descriptors = features.descriptors.rowRange(0, 10);
  EXPECT_THROW(keypoints_with_depth(short_descriptors, r.frame, 0.1, 8.0), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::loop_closure
