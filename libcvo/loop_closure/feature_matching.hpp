#pragma once
// Descriptor matching between two keyframes (paper section 5, as ORB-SLAM2): for each query
// descriptor the two nearest train descriptors by Hamming distance (brute force, OpenCV's
// BFMatcher), kept when d_best < ratio * d_second (Lowe's ratio test, Table 1: 0.7): a match that
// is not clearly better than the runner-up is ambiguous (repeated texture) and dropped. A query
// with fewer than two train descriptors to compare has no match.
#include <vector>

#include <opencv2/core/mat.hpp>

namespace cvo::loop_closure {

struct FeatureMatch {
  int query = 0;  // row of the query descriptors
  int train = 0;  // row of the train descriptors
  int distance = 0;
};

/// Ratio-test matches of CV_8UC1 n x 32 descriptor matrices, in query order. Deterministic.
std::vector<FeatureMatch> ratio_matches(const cv::Mat& query, const cv::Mat& train, double ratio);

}  // namespace cvo::loop_closure
