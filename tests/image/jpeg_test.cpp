// JPEG through TurboJPEG: round trips within JPEG's loss, the same pixels as OpenCV's decoder
// (the same libjpeg-turbo underneath) both ways, and broken streams answered with a message.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/image/jpeg.hpp"
#include "tests/image/test_images.hpp"

namespace cvo::image {
namespace {

using test::Bytes;

Bytes encoded(const cv::Mat& bgr, int quality = 90) {
  Bytes jpeg;
  EXPECT_EQ(encode_jpeg(bgr, quality, jpeg), "");
  return jpeg;
}

Bytes opencv_jpeg(const cv::Mat& image, int quality = 90) {
  Bytes jpeg;
  EXPECT_TRUE(cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, quality}));
  return jpeg;
}

double mean_difference(const cv::Mat& a, const cv::Mat& b) {
  return cv::norm(a, b, cv::NORM_L1) / static_cast<double>(a.total() * a.channels());
}

TEST(Jpeg, RoundTripIsWithinJpegsLoss) {
  const cv::Mat bgr = test::scene();
  cv::Mat back;
  ASSERT_EQ(decode_jpeg(encoded(bgr, 90), back), "");
  ASSERT_EQ(back.type(), CV_8UC3);
  ASSERT_EQ(back.size(), bgr.size());
  EXPECT_LT(mean_difference(back, bgr), 3.0);
  cv::Mat coarse;
  ASSERT_EQ(decode_jpeg(encoded(bgr, 10), coarse), "");
  EXPECT_GT(mean_difference(coarse, bgr), mean_difference(back, bgr)) << "quality must reach the encoder";
}

TEST(Jpeg, OpenCvDecodesWhatWeWriteAsWeDo) {
  const Bytes jpeg = encoded(test::scene());
  cv::Mat ours;
  ASSERT_EQ(decode_jpeg(jpeg, ours), "");
  const cv::Mat theirs = cv::imdecode(jpeg, cv::IMREAD_COLOR);
  ASSERT_EQ(theirs.size(), ours.size());
  EXPECT_LE(test::max_difference(ours, theirs), 1);
}

TEST(Jpeg, WeDecodeWhatOpenCvWritesAsItDoes) {
  const cv::Mat bgr = test::scene();
  const Bytes jpeg = opencv_jpeg(bgr);
  cv::Mat ours;
  ASSERT_EQ(decode_jpeg(jpeg, ours), "");
  EXPECT_LE(test::max_difference(ours, cv::imdecode(jpeg, cv::IMREAD_COLOR)), 1);
  EXPECT_LT(mean_difference(ours, bgr), 3.0);
}

TEST(Jpeg, GreyJpegDecodesToBgr) {
  cv::Mat grey(48, 64, CV_8UC1);
  for (int r = 0; r < grey.rows; ++r)
    for (int c = 0; c < grey.cols; ++c) grey.at<std::uint8_t>(r, c) = std::uint8_t(2 * r + 3 * c);
  const Bytes jpeg = opencv_jpeg(grey);
  ImageHeader header;
  ASSERT_EQ(read_jpeg_header(jpeg, header), "");
  EXPECT_EQ(header.channels, 1);
  cv::Mat bgr;
  ASSERT_EQ(decode_jpeg(jpeg, bgr), "");
  ASSERT_EQ(bgr.type(), CV_8UC3);
  EXPECT_LE(test::max_difference(bgr, cv::imdecode(jpeg, cv::IMREAD_COLOR)), 1);
}

TEST(Jpeg, HeaderGivesTheSize) {
  ImageHeader header;
  ASSERT_EQ(read_jpeg_header(encoded(test::scene(30, 50)), header), "");
  EXPECT_EQ(header.width, 50);
  EXPECT_EQ(header.height, 30);
  EXPECT_EQ(header.channels, 3);
}

TEST(Jpeg, AnImageOfTheRightSizeIsDecodedIntoItsOwnBuffer) {
  const Bytes jpeg = encoded(test::scene());
  cv::Mat image(48, 64, CV_8UC3, cv::Scalar::all(0));
  const auto* buffer = image.data;
  ASSERT_EQ(decode_jpeg(jpeg, image), "");
  EXPECT_EQ(image.data, buffer);
  EXPECT_LT(mean_difference(image, test::scene()), 3.0);
}

TEST(Jpeg, AViewWithRowPaddingEncodesAndDecodes) {
  const cv::Mat big = test::scene(96, 128);
  const cv::Mat view = big(cv::Rect(8, 16, 64, 48));
  cv::Mat back;
  ASSERT_EQ(decode_jpeg(encoded(view), back), "");
  EXPECT_LT(mean_difference(back, view), 3.0);
  cv::Mat into_view = cv::Mat(96, 128, CV_8UC3, cv::Scalar::all(0))(cv::Rect(8, 16, 64, 48));
  ASSERT_EQ(decode_jpeg(encoded(view), into_view), "");
  EXPECT_EQ(test::max_difference(into_view, back), 0);
}

TEST(Jpeg, AnotherSizeThanExpectedIsRefusedFromTheHeader) {
  cv::Mat image;
  EXPECT_EQ(decode_jpeg(encoded(test::scene()), image, {640, 480}), "JPEG: image is 64x48, expected 640x480");
  EXPECT_TRUE(image.empty());
}

// A truncated scan: libjpeg fills the missing rows with grey and warns. Refused unless the caller
// accepts warnings (a V4L2 camera's frames).
TEST(Jpeg, TruncatedScanIsRefusedUnlessWarningsAreAccepted) {
  const Bytes jpeg = encoded(test::noise(CV_8UC3, 96, 128));
  const Bytes truncated(jpeg.begin(), jpeg.begin() + std::ptrdiff_t(jpeg.size() * 2 / 3));
  cv::Mat image;
  const std::string bad = decode_jpeg(truncated, image);
  EXPECT_NE(bad.find("Premature end of JPEG file"), std::string::npos) << bad;
  EXPECT_EQ(decode_jpeg(truncated, image, {}, JpegWarnings::kAccept), "");
  EXPECT_EQ(image.size(), cv::Size(128, 96));
}

TEST(Jpeg, EveryTruncationIsAMessage) {
  const Bytes jpeg = encoded(test::scene());
  for (std::size_t size = 0; size < jpeg.size() - 2; ++size) {  // the last two bytes are EOI
    cv::Mat image;
    const std::string bad = decode_jpeg({jpeg.data(), size}, image);
    ASSERT_EQ(bad.rfind("JPEG: ", 0), 0u) << size << " of " << jpeg.size() << " bytes: " << bad;
  }
}

TEST(Jpeg, CorruptBytesAreAMessageOrAnImageNeverACrash) {
  const Bytes good = encoded(test::scene());
  cv::RNG rng(5);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Bytes bad = good;
    for (int k = 0; k < 4; ++k) bad[std::size_t(rng.uniform(0, int(bad.size())))] = std::uint8_t(rng.uniform(0, 256));
    cv::Mat image;
    const std::string message = decode_jpeg(bad, image);
    if (message.empty()) {
      EXPECT_EQ(image.type(), CV_8UC3);  // some bytes (quantisation, pixels) are only other pixels
    } else {
      EXPECT_EQ(message.rfind("JPEG: ", 0), 0u) << message;
      ++refused;
    }
  }
  EXPECT_GT(refused, 0);
  cv::Mat image;
  EXPECT_EQ(decode_jpeg(Bytes{'n', 'o', 'p', 'e'}, image), "JPEG: no start-of-image marker");
  EXPECT_EQ(decode_jpeg(Bytes{}, image), "JPEG: no start-of-image marker");
}

TEST(Jpeg, EncodingRefusesWhatItCannotWrite) {
  Bytes jpeg;
  EXPECT_NE(encode_jpeg(cv::Mat(4, 4, CV_8UC1), 90, jpeg).find("CV_8UC3"), std::string::npos);
  EXPECT_NE(encode_jpeg(cv::Mat(), 90, jpeg).find("CV_8UC3"), std::string::npos);
  EXPECT_NE(encode_jpeg(cv::Mat(4, 4, CV_8UC3), 101, jpeg).find("0..100"), std::string::npos);
}

}  // namespace
}  // namespace cvo::image
