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

/// cv::ORB's settings; the defaults (core::LoopVerificationParameters' orb_*) are ORB-SLAM2's
/// feature count with OpenCV's other defaults.
struct OrbParameters {
  int features = core::LoopVerificationParameters{}.orb_features;  // at most this many, strongest first
  float scale_factor = static_cast<float>(core::LoopVerificationParameters{}.orb_scale_factor);  // between levels
  int levels = core::LoopVerificationParameters{}.orb_levels;                  // pyramid levels
  int edge_threshold = core::LoopVerificationParameters{}.orb_edge_threshold;  // border without features, pixels
  int fast_threshold = core::LoopVerificationParameters{}.orb_fast_threshold;  // FAST intensity threshold
};

/// Keypoints with one descriptor row each: descriptors is CV_8UC1, keypoints.size() x 32 (256
/// bits), also when there are no keypoints (0 x 32).
struct OrbFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

/// The ORB features of a BGR (CV_8UC3) or grey (CV_8UC1) image. Throws std::invalid_argument on
/// another image type or bad parameters. An image without texture gives no features, not an error.
OrbFeatures extract_orb(const cv::Mat& image, const OrbParameters& parameters = {});

}  // namespace cvo::loop_closure
