#pragma once
// Images for the codec tests: deterministic noise (incompressible, every value a PNG must keep),
// a smooth scene (what a camera sees, what JPEG is made for), and byte helpers.
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace cvo::image::test {

using Bytes = std::vector<std::uint8_t>;

inline cv::Mat noise(int type, int rows = 48, int cols = 64) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(23);
  rng.fill(m, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 65536 : 256);
  if (type == CV_16UC1) {  // the extremes, so that a lost byte or a swapped order shows
    m.at<std::uint16_t>(0, 0) = 0;
    m.at<std::uint16_t>(0, 1) = 65535;
    m.at<std::uint16_t>(0, 2) = 0x0102;
  }
  return m;
}

inline cv::Mat scene(int rows = 48, int cols = 64) {
  cv::Mat m(rows, cols, CV_8UC3);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      m.at<cv::Vec3b>(r, c) =
          cv::Vec3b(std::uint8_t(255 * c / cols), std::uint8_t(255 * r / rows),
                    cv::saturate_cast<std::uint8_t>(128 + 60 * std::sin(r / 5.0) * std::cos(c / 7.0)));
  return m;
}

inline double max_difference(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF); }

}  // namespace cvo::image::test
