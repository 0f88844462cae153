#include "libcvo/sim/colour_noise.hpp"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace cvo::sim {
namespace {

// The model with every term at work (the defaults have no shot noise and no correlation).
ColourNoiseOptions on() {
  ColourNoiseOptions options;
  options.enabled = true;
  options.read_sigma_levels = 2.0;
  options.shot_levels = 0.25;
  options.channel_correlation = 0.9;
  return options;
}

// The defaults are fr1's measured grey noise, 0.79 levels on its flattest 8x8 patches
// (colour_noise.hpp): a flat field's grey spreads by 0.67 * 1.2 = 0.8 levels.
TEST(ColourNoise, TheDefaultsGiveAGreyNoiseOfAboutALevelAsFr1sRealFramesShow) {
  ColourNoiseOptions defaults;
  defaults.enabled = true;
  const cv::Mat bytes = develop_colour(cv::Mat(200, 200, CV_64FC3, cv::Scalar::all(0.45)), 1.0, defaults, 5);
  cv::Mat grey;
  cv::cvtColor(bytes, grey, cv::COLOR_BGR2GRAY);
  cv::Scalar mean, std;
  cv::meanStdDev(grey, mean, std);
  EXPECT_NEAR(std[0], 0.8, 0.15);
}

TEST(ColourNoise, SigmaIsReadPlusShotNoise) {
  EXPECT_DOUBLE_EQ(colour_noise_sigma(on(), 0.0), 2.0);
  EXPECT_DOUBLE_EQ(colour_noise_sigma(on(), 200.0), std::sqrt(4.0 + 0.25 * 200.0));
  EXPECT_GT(colour_noise_sigma(on(), 200.0), colour_noise_sigma(on(), 50.0)) << "signal-dependent";
}

TEST(ColourNoise, WithoutNoiseAndWithGainOneItIsPlainQuantisation) {
  cv::Mat linear(4, 4, CV_64FC3);
  for (int i = 0; i < 16; ++i)
    linear.at<cv::Vec3d>(i / 4, i % 4) = cv::Vec3d(i / 15.0, 0.5 + i / 100.0, 1.2 - i / 10.0);
  const cv::Mat bytes = develop_colour(linear, 1.0, {}, 0);
  for (int i = 0; i < 16; ++i)
    for (int c = 0; c < 3; ++c) {
      const double x = linear.at<cv::Vec3d>(i / 4, i % 4)[c];
      EXPECT_EQ(bytes.at<cv::Vec3b>(i / 4, i % 4)[c], std::lround(std::clamp(x, 0.0, 1.0) * 255.0));
    }
}

// A flat grey field: levels spread by the model's sigma around the signal, unbiased, the channels'
// noise correlated by rho; another seed, other noise.
TEST(ColourNoise, AFlatFieldSpreadsByTheModelWithCorrelatedChannels) {
  const cv::Mat linear(200, 200, CV_64FC3, cv::Scalar::all(0.45));
  const cv::Mat bytes = develop_colour(linear, 1.0, on(), 5);
  double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0}, cross = 0;
  for (int v = 0; v < bytes.rows; ++v)
    for (int u = 0; u < bytes.cols; ++u) {
      const cv::Vec3b p = bytes.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) {
        sum[c] += p[c];
        sum2[c] += p[c] * p[c];
      }
      cross += (p[0] - 114.75) * (p[1] - 114.75);
    }
  const double n = static_cast<double>(bytes.total()), level = 0.45 * 255, sigma = colour_noise_sigma(on(), level);
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / n, std = std::sqrt(sum2[c] / n - mean * mean);
    EXPECT_NEAR(mean, level, 0.1) << c;
    EXPECT_NEAR(std, std::sqrt(sigma * sigma + 1.0 / 12.0), 0.05 * sigma) << c;  // plus rounding
  }
  EXPECT_NEAR(cross / n / (sigma * sigma), 0.9, 0.05) << "channel correlation";
  EXPECT_GT(cv::norm(bytes, develop_colour(linear, 1.0, on(), 6), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(bytes, develop_colour(linear, 1.0, on(), 5), cv::NORM_INF), 0.0);
}

TEST(ColourNoise, GainMultipliesAndClipsAtWhite) {
  const cv::Mat linear(2, 2, CV_64FC3, cv::Scalar(0.1, 0.3, 0.6));
  const cv::Mat bytes = develop_colour(linear, 2.0, {}, 0);
  EXPECT_EQ(bytes.at<cv::Vec3b>(0, 0), cv::Vec3b(51, 153, 255));  // 0.2, 0.6, 1.2 -> clipped
}

}  // namespace
}  // namespace cvo::sim
