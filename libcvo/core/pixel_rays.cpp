#include "libcvo/core/pixel_rays.hpp"

#include <opencv2/calib3d.hpp>

namespace cvo::core {

std::vector<float> undistorted_pixel_rays(const Intrinsics& K) {
  const auto n = static_cast<std::size_t>(K.width) * static_cast<std::size_t>(K.height);
  cv::Mat pixels(static_cast<int>(n), 1, CV_32FC2);
  auto* p = pixels.ptr<cv::Vec2f>();
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) *p++ = {static_cast<float>(u), static_cast<float>(v)};
  const cv::Matx33d camera(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  std::vector<float> rays(2 * n);
  cv::Mat out(static_cast<int>(n), 1, CV_32FC2, rays.data());  // written in place
  cv::undistortPoints(pixels, out, camera, K.distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-4));
  return rays;
}

}  // namespace cvo::core
