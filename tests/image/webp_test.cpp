// WebP through libwebp: lossless WebP written by OpenCV reads back bit-exact, the embedded
// sample's frames read as OpenCV reads them, and broken files are a message.
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/image/webp.hpp"
#include "tests/image/test_images.hpp"

namespace cvo::image {
namespace {

using test::Bytes;

Bytes lossless_webp(const cv::Mat& image) {
  Bytes webp;
  EXPECT_TRUE(cv::imencode(".webp", image, webp, {cv::IMWRITE_WEBP_QUALITY, 101}));  // above 100: lossless
  return webp;
}

TEST(Webp, LosslessWebpReadsBackBitExact) {
  const cv::Mat bgr = test::noise(CV_8UC3);
  cv::Mat back;
  ASSERT_EQ(decode_webp(lossless_webp(bgr), back), "");
  ASSERT_EQ(back.type(), CV_8UC3);
  EXPECT_EQ(test::max_difference(back, bgr), 0);
}

TEST(Webp, TheSamplesColourReadsAsOpenCvReadsIt) {
  const std::string file = CVO_TEST_DATA_DIR "/fr1_rpy_50/rgb/1305031229.528748.webp";
  std::ifstream in(file, std::ios::binary);
  ASSERT_TRUE(in) << file;
  const Bytes webp{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  cv::Mat ours(480, 640, CV_8UC3);
  const auto* buffer = ours.data;
  ASSERT_EQ(decode_webp(webp, ours, {640, 480}), "");
  EXPECT_EQ(ours.data, buffer) << "decoded into the image of its size";
  EXPECT_EQ(test::max_difference(ours, cv::imread(file, cv::IMREAD_COLOR)), 0);
}

TEST(Webp, AnotherSizeThanExpectedIsRefusedFromTheHeader) {
  cv::Mat image;
  EXPECT_EQ(decode_webp(lossless_webp(test::noise(CV_8UC3)), image, {640, 480}),
            "WebP: image is 64x48, expected 640x480");
  EXPECT_TRUE(image.empty());
}

TEST(Webp, EveryTruncationIsAMessage) {
  const Bytes webp = lossless_webp(test::noise(CV_8UC3));
  for (std::size_t size = 0; size < webp.size(); ++size) {
    cv::Mat image;
    const std::string bad = decode_webp({webp.data(), size}, image);
    ASSERT_EQ(bad.rfind("WebP: ", 0), 0u) << size << " of " << webp.size() << " bytes: " << bad;
  }
  cv::Mat image;
  EXPECT_EQ(decode_webp(Bytes{'R', 'I', 'F', 'F'}, image), "WebP: no RIFF/WEBP signature");
}

}  // namespace
}  // namespace cvo::image
