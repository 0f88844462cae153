#pragma once
// What the tests of the emulated V4L2 cameras share: the emulator's stats (looked up in the
// process, so a test knows the emulator is loaded), and which entry of the clip a frame shows.
// The cameras themselves are in v4l2_emulator_test.cpp (the environment the tests run in).
#include <dlfcn.h>

#include <cstddef>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "libcvo/io/tum_dataset.hpp"
#include "tests/support/v4l2_emulator/stats.h"

namespace cvo::testing {

inline const std::filesystem::path kEmulatedClip = std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

/// The emulator's stats of `node`; fails the test when the emulator is not loaded.
inline cvo_v4l2_emulator_node_stats emulator_stats(const std::string& node) {
  cvo_v4l2_emulator_node_stats s{};
  const auto stats = reinterpret_cast<cvo_v4l2_emulator_stats_fn>(::dlsym(RTLD_DEFAULT, "cvo_v4l2_emulator_stats"));
  if (stats == nullptr) {
    ADD_FAILURE() << "the V4L2 emulator is not loaded (LD_PRELOAD=" CVO_V4L2_EMULATOR_PRELOAD ")";
    return s;
  }
  EXPECT_EQ(stats(node.c_str(), &s), 0) << node << " is not an emulated node";
  return s;
}

/// The clip's images, depth in millimetres as the emulated cameras send it.
struct ClipImages {
  std::vector<cv::Mat> bgr, depth_mm;

  ClipImages() {
    const auto clip = io::TumSequence::open(kEmulatedClip);
    for (std::size_t i = 0; i < clip.size(); ++i) {
      const auto frame = clip.read(i);
      bgr.push_back(frame.bgr);
      cv::Mat mm;
      frame.depth.convertTo(mm, CV_16U, 1000.0 / frame.intrinsics.depth_scale);
      depth_mm.push_back(mm);
    }
  }

  /// The entry whose image is closest to `image` (mean absolute difference) and that distance.
  static std::pair<std::size_t, double> closest(const std::vector<cv::Mat>& entries, const cv::Mat& image) {
    std::pair<std::size_t, double> best{0, std::numeric_limits<double>::infinity()};
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (entries[i].size() != image.size() || entries[i].type() != image.type()) continue;
      cv::Mat diff;
      cv::absdiff(entries[i], image, diff);
      const auto d = cv::mean(diff);
      const double distance = (d[0] + d[1] + d[2]) / image.channels();
      if (distance < best.second) best = {i, distance};
    }
    return best;
  }
};

}  // namespace cvo::testing
