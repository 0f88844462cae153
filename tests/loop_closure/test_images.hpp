#pragma once
// Images of the loop-closure tests: real frames of the embedded fr1/rpy sample, and rendered
// frames of the synthetic textured room (a clearly different image family).
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/loop_closure/orb_features.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"

namespace cvo::loop_closure::testing {

inline std::filesystem::path sample_dir() { return std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50"; }

/// Colour frame i (0..49) of tests/data/fr1_rpy_50, BGR.
inline cv::Mat sample_frame(std::size_t i) {
  const auto files = io::TumSequence::open(sample_dir()).files();
  cv::Mat bgr = cv::imread(files.at(i).rgb.string(), cv::IMREAD_COLOR);
  EXPECT_FALSE(bgr.empty()) << files.at(i).rgb;
  return bgr;
}

/// Frame at `seconds` of the textured room's orbit (one colour ray per pixel: fast enough).
inline cv::Mat room_frame(double seconds) {
  const sim::Scene scene = sim::make_scene(sim::SceneKind::textured_room, 3);
  sim::RenderOptions options;
  options.supersample = false;
  const core::Intrinsics camera{525.0, 525.0, 319.5, 239.5, 640, 480, 5000.0};
  return sim::render(scene, camera, sim::path_pose(sim::PathKind::orbit, seconds), {}, 0, options).bgr;
}

inline cv::Mat orb(const cv::Mat& bgr) { return extract_orb(bgr).descriptors; }

}  // namespace cvo::loop_closure::testing
