#include "libcvo/eval/plot.hpp"

#include <filesystem>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "eval/test_trajectories.hpp"
#include "libcvo/io/input_error.hpp"

namespace cvo::eval {
namespace {

using testing::helix;
using testing::make;

// Pixels close to a colour (anti-aliasing blends the edges; the line centres are pure).
int count_colour(const cv::Mat& img, const cv::Vec3b& bgr) {
  int n = 0;
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c)
      if (cv::norm(cv::Vec3i(img.at<cv::Vec3b>(r, c)) - cv::Vec3i(bgr), cv::NORM_INF) < 40) ++n;
  return n;
}

struct Fixture {
  core::Trajectory gt = make(80, helix);
  core::Trajectory est = make(80, [](double t) {
    return core::SE3::from_translation({0.05 * std::sin(3 * t), 0.02 * t, 0}) * helix(t);
  });
  AteResult ate = absolute_trajectory_error(gt, est);
};

TEST(Plot, RendersBothPanelsInTheRequestedSize) {
  const Fixture f;
  const cv::Mat img = render_evaluation_plot(f.gt, f.est, f.ate);
  EXPECT_EQ(img.cols, 1200);
  EXPECT_EQ(img.rows, 600);
  EXPECT_EQ(img.type(), CV_8UC3);
  EXPECT_GT(count_colour(img, {0, 0, 0}), 1000);     // ground truth, axes, text
  EXPECT_GT(count_colour(img, {200, 60, 0}), 1000);  // estimate and error curve
  EXPECT_GT(count_colour(img, {0, 0, 220}), 50);     // differences
  // Left half holds the red differences; the right half has none.
  EXPECT_EQ(count_colour(img(cv::Rect(600, 0, 600, 600)), {0, 0, 220}), 0);
  const cv::Mat other = render_evaluation_plot(f.gt, f.est, f.ate, {.size = {800, 400}, .title = "x"});
  EXPECT_EQ(other.size(), cv::Size(800, 400));
}

TEST(Plot, DegenerateInputStillDraws) {
  // A trajectory standing still: zero spans on every axis, zero errors.
  const auto still = make(10, [](double) { return core::SE3::from_translation({1, 2, 3}); });
  const auto ate = absolute_trajectory_error(still, still);
  EXPECT_EQ(render_evaluation_plot(still, still, ate).size(), cv::Size(1200, 600));
}

TEST(Plot, WritesAReadablePngAndNamesAnUnwritableFile) {
  const Fixture f;
  const auto png = std::filesystem::temp_directory_path() / ("cvo_plot_test_" + std::to_string(::getpid()) + ".png");
  write_evaluation_plot(png, f.gt, f.est, f.ate);
  const cv::Mat back = cv::imread(png.string());
  std::filesystem::remove(png);
  EXPECT_EQ(back.size(), cv::Size(1200, 600));
  EXPECT_THROW(write_evaluation_plot("/nonexistent/dir/plot.png", f.gt, f.est, f.ate), io::InputError);
  EXPECT_THROW(render_evaluation_plot(f.gt, f.est, f.ate, {.size = {100, 100}}), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::eval
