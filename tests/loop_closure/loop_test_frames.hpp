#pragma once
// Keyframes for the loop-verification tests: real fr1/rpy frames with the interpolated ground
// truth, and rendered frames of the textured room's orbit with the exact one.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numbers>

#include <gtest/gtest.h>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/loop_closure/loop_verification.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"
#include "loop_closure/test_images.hpp"

namespace cvo::loop_closure::testing {

inline double deg(double rad) { return rad * 180.0 / std::numbers::pi; }

/// A keyframe as the SLAM front end would hand it over, with its true pose.
struct TestKeyframe {
  core::RgbdFrame frame;
  registration::PointCloud cloud{8192};
  core::SE3 truth;  // T_world_camera
};

inline registration::PointCloud select_points(const core::RgbdFrame& frame) {
  registration::PointSelector selector(frame.bgr.cols, frame.bgr.rows, core::SelectionParameters{});
  registration::PointCloud cloud(8192);
  const auto status = selector.select(frame, cloud).status;
  EXPECT_TRUE(status == registration::SelectionStatus::kOk) << registration::to_string(status);
  return cloud;
}

inline core::SE3 groundtruth_at(const core::Trajectory& gt, double t) {
  const auto it = std::lower_bound(gt.begin(), gt.end(), t, [](const auto& p, double v) { return p.timestamp < v; });
  if (it == gt.begin()) return gt.front().pose;
  if (it == gt.end()) return gt.back().pose;
  const auto& a = *(it - 1);
  const auto& b = *it;
  return core::interpolate(a.pose, b.pose, (t - a.timestamp) / (b.timestamp - a.timestamp));
}

/// Frame i (0..49) of tests/data/fr1_rpy_50.
inline TestKeyframe real_keyframe(std::size_t i) {
  const auto sequence = io::TumSequence::open(sample_dir());
  TestKeyframe k;
  k.frame = sequence.read(i);
  k.cloud = select_points(k.frame);
  k.truth = groundtruth_at(sequence.groundtruth(), k.frame.timestamp);
  return k;
}

/// The textured room seen from the orbit at `seconds`, with Kinect-like depth noise.
inline TestKeyframe rendered_keyframe(double seconds) {
  static const sim::Scene scene = sim::make_scene(sim::SceneKind::textured_room, 3);
  sim::RenderOptions options;
  options.supersample = false;  // one ray per pixel: fast enough
  sim::NoiseOptions noise;
  noise.enabled = true;
  const core::Intrinsics camera{525.0, 525.0, 319.5, 239.5, 640, 480, 5000.0};
  TestKeyframe k;
  k.truth = sim::path_pose(sim::PathKind::orbit, seconds);
  k.frame = sim::render(scene, camera, k.truth, noise, static_cast<std::uint64_t>(seconds * 1000), options);
  k.frame.intrinsics = camera;
  k.cloud = select_points(k.frame);
  return k;
}

inline LoopKeyframe loop_keyframe(std::int64_t id, const TestKeyframe& k, const core::SE3& pose,
                                  const LoopDetectorParameters& parameters = {}) {
  return make_loop_keyframe(id, extract_orb(k.frame.bgr, parameters.verification), k.frame, k.cloud, pose, parameters);
}

/// Odometry-like drift: the true pose moved by exp(s ξ) in the world, ξ = 5 cm and 3° in total.
inline core::SE3 drifted(const core::SE3& truth, double s) {
  const core::Vector6d xi = (core::Vector6d() << 0.03, -0.03, 0.02, 0.02, -0.03, 0.03).finished();
  return core::SE3::exp(s * xi) * truth;
}

/// Error of a measured T_from_to against the truth.
struct PoseError {
  double translation_m = 0, rotation_deg = 0;
};
inline PoseError pose_error(const core::SE3& measured, const core::SE3& truth) {
  const auto e = truth.inverse() * measured;
  return {e.translation().norm(), deg(e.angle())};
}

}  // namespace cvo::loop_closure::testing
