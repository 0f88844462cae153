#include "libcvo/loop_closure/orb_features.hpp"

#include <stdexcept>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

namespace cvo::loop_closure {

OrbFeatures extract_orb(const cv::Mat& image, const core::LoopVerificationParameters& p) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 1))
    throw std::invalid_argument("extract_orb: needs a non-empty CV_8UC3 (BGR) or CV_8UC1 image");
  const auto scale_factor = static_cast<float>(p.orb_scale_factor);  // cv::ORB's type
  if (p.orb_features < 1 || p.orb_levels < 1 || !(scale_factor > 1.0f) || p.orb_edge_threshold < 0 ||
      p.orb_fast_threshold < 1)
    throw std::invalid_argument("extract_orb: bad ORB parameters");
  cv::Mat grey = image;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);

  // A fresh detector per call: cheap next to detection, and keeps this function free of state.
  const auto orb = cv::ORB::create(p.orb_features, scale_factor, p.orb_levels, p.orb_edge_threshold, 0, 2,
                                   cv::ORB::HARRIS_SCORE, 31, p.orb_fast_threshold);
  OrbFeatures f;
  orb->detectAndCompute(grey, cv::noArray(), f.keypoints, f.descriptors);
  if (f.descriptors.empty()) f.descriptors = cv::Mat(0, 32, CV_8UC1);  // one shape for "none"
  return f;
}

}  // namespace cvo::loop_closure
