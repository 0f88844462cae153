#include "libcvo/loop_closure/feature_matching.hpp"

#include <opencv2/features2d.hpp>

namespace cvo::loop_closure {

std::vector<FeatureMatch> ratio_matches(const cv::Mat& query, const cv::Mat& train, double ratio) {
  std::vector<FeatureMatch> out;
  if (query.rows == 0 || train.rows < 2) return out;
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, train, knn, 2);
  for (const auto& m : knn)
    if (m.size() == 2 && m[0].distance < ratio * m[1].distance)
      out.push_back({m[0].queryIdx, m[0].trainIdx, static_cast<int>(m[0].distance)});
  return out;
}

}  // namespace cvo::loop_closure
