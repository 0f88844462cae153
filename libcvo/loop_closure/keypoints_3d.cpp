#include "libcvo/loop_closure/keypoints_3d.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace cvo::loop_closure {

Keypoints3d keypoints_with_depth(const OrbFeatures& features, const core::RgbdFrame& frame, double min_depth_m,
                                 double max_depth_m) {
  const cv::Mat& depth = frame.depth;
  if (depth.type() != CV_16UC1 || depth.size() != frame.bgr.size())
    throw std::invalid_argument("keypoints_with_depth: depth must be CV_16UC1 of the colour image's size");
  if (features.descriptors.type() != CV_8UC1 || features.descriptors.cols != 32 ||
      static_cast<std::size_t>(features.descriptors.rows) != features.keypoints.size())
    throw std::invalid_argument("keypoints_with_depth: needs one 32-byte CV_8UC1 descriptor row per keypoint");
  const auto& K = frame.intrinsics;
  if (const auto error = K.validate(); !error.empty()) throw std::invalid_argument("keypoints_with_depth: " + error);

  Keypoints3d out;
  std::vector<int> rows;
  for (std::size_t k = 0; k < features.keypoints.size(); ++k) {
    const cv::Point2f& pt = features.keypoints[k].pt;
    const int u = static_cast<int>(std::lround(pt.x)), v = static_cast<int>(std::lround(pt.y));
    if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
    const std::uint16_t raw = depth.at<std::uint16_t>(v, u);
    const double z = raw / K.depth_scale;
    if (raw == 0 || z < min_depth_m || z > max_depth_m) continue;
    out.points.emplace_back((pt.x - K.cx) * z / K.fx, (pt.y - K.cy) * z / K.fy, z);
    rows.push_back(static_cast<int>(k));
  }
  out.descriptors = cv::Mat(static_cast<int>(rows.size()), 32, CV_8UC1);
  for (std::size_t r = 0; r < rows.size(); ++r)
    features.descriptors.row(rows[r]).copyTo(out.descriptors.row(static_cast<int>(r)));
  return out;
}

}  // namespace cvo::loop_closure
