#pragma once
// ORB features (Rublee et al. 2011) of a keyframe, through OpenCV: FAST corners on an 8-level
// image pyramid, ranked by the Harris score, each described by a 256-bit rotated BRIEF string.
// Loop closure (paper section 5) turns the descriptors into a bag-of-words vector
// (vocabulary.hpp) and later matches them between keyframes by Hamming distance.
#include <vector>

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

#include "libcvo/core/parameters.hpp"

namespace cvo::loop_closure {

/// Keypoints with one descriptor row each: descriptors is CV_8UC1, keypoints.size() x 32 (256
/// bits), also when there are no keypoints (0 x 32).
struct OrbFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

/// The ORB features of a BGR (CV_8UC3) or grey (CV_8UC1) image, with cv::ORB's settings from the
/// orb_* members of `parameters` (the rest is loop verification's; the defaults are ORB-SLAM2's
/// feature count with OpenCV's other defaults). Throws std::invalid_argument on another image type
/// or bad parameters. An image without texture gives no features, not an error.
OrbFeatures extract_orb(const cv::Mat& image, const core::LoopVerificationParameters& parameters = {});

}  // namespace cvo::loop_closure
