// ORB extraction: shapes and types the vocabulary relies on, and the parameters taking effect.
#include "libcvo/loop_closure/orb_features.hpp"

#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "loop_closure/test_images.hpp"

namespace cvo::loop_closure {
namespace {

TEST(OrbFeatures, RealFrameGivesUpToTheRequestedNumberOf256BitDescriptors) {
  const cv::Mat bgr = testing::sample_frame(0);
  const OrbFeatures f = extract_orb(bgr);
  EXPECT_GT(f.keypoints.size(), 500u);  // a textured office: close to the 1000 asked for
  EXPECT_LE(f.keypoints.size(), 1000u);
  EXPECT_EQ(f.descriptors.type(), CV_8UC1);
  EXPECT_EQ(f.descriptors.cols, 32);
  EXPECT_EQ(static_cast<std::size_t>(f.descriptors.rows), f.keypoints.size());

  const OrbFeatures few = extract_orb(bgr, {.orb_features = 100});
  EXPECT_LE(few.keypoints.size(), 100u);
  EXPECT_GT(few.keypoints.size(), 50u);
}

TEST(OrbFeatures, GreyInputGivesTheSameFeaturesAsItsColourImage) {
  const cv::Mat bgr = testing::sample_frame(10);
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  const OrbFeatures a = extract_orb(bgr), b = extract_orb(grey);
  ASSERT_EQ(a.descriptors.size(), b.descriptors.size());
  EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0.0);
}

TEST(OrbFeatures, TexturelessImageGivesAnEmpty0x32Matrix) {
  const OrbFeatures f = extract_orb(cv::Mat(480, 640, CV_8UC3, cv::Scalar(90, 120, 150)));
  EXPECT_TRUE(f.keypoints.empty());
  EXPECT_EQ(f.descriptors.rows, 0);
  EXPECT_EQ(f.descriptors.cols, 32);
  EXPECT_EQ(f.descriptors.type(), CV_8UC1);
}

TEST(OrbFeatures, RejectsOtherImageTypesAndBadParameters) {
  EXPECT_THROW(extract_orb(cv::Mat(48, 64, CV_32FC1, cv::Scalar(0.5))), std::invalid_argument);
  EXPECT_THROW(extract_orb(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(extract_orb(cv::Mat(48, 64, CV_8UC3), {.orb_features = 0}), std::invalid_argument);
  EXPECT_THROW(extract_orb(cv::Mat(48, 64, CV_8UC3), {.orb_scale_factor = 1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::loop_closure
