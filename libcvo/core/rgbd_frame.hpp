#pragma once
// One RGB-D frame as drivers and dataset readers produce it.
#include <cstdint>

#include <opencv2/core/mat.hpp>

#include "libcvo/core/camera.hpp"

namespace cvo::core {

struct RgbdFrame {
  std::uint64_t index = 0;  // position in its stream, from 0
  double timestamp = 0;     // seconds; the colour image's stamp
  double depth_timestamp = 0;
  cv::Mat bgr;    // CV_8UC3, OpenCV's BGR channel order
  cv::Mat depth;  // CV_16UC1, raw units (intrinsics.depth_scale per metre), 0 = no measurement
  Intrinsics intrinsics;
};

}  // namespace cvo::core
