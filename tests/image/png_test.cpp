// PNG through libpng: bit-exact round trips of colour and 16-bit depth, OpenCV reading what we
// write and we reading what it writes, and broken files answered with a message.
#include <zlib.h>

#include <algorithm>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/image/png.hpp"
#include "tests/image/test_images.hpp"

namespace cvo::image {
namespace {

using test::Bytes;

Bytes encoded(const cv::Mat& image, PngPixels pixels, int compression = 1) {
  Bytes png;
  EXPECT_EQ(encode_png(image, pixels, compression, png), "");
  return png;
}

Bytes opencv_png(const cv::Mat& image) {
  Bytes png;
  EXPECT_TRUE(cv::imencode(".png", image, png));
  return png;
}

TEST(Png, ColourRoundTripIsBitExactAtEveryCompression) {
  const cv::Mat bgr = test::noise(CV_8UC3);
  for (const int compression : {0, 1, 9}) {
    cv::Mat back;
    ASSERT_EQ(decode_png(encoded(bgr, PngPixels::kBgr8, compression), PngPixels::kBgr8, back), "");
    ASSERT_EQ(back.type(), CV_8UC3);
    EXPECT_EQ(test::max_difference(back, bgr), 0) << "compression " << compression;
  }
}

TEST(Png, DepthRoundTripIsBitExact) {
  const cv::Mat depth = test::noise(CV_16UC1);
  cv::Mat back;
  ASSERT_EQ(decode_png(encoded(depth, PngPixels::kGrey16), PngPixels::kGrey16, back), "");
  ASSERT_EQ(back.type(), CV_16UC1);
  EXPECT_EQ(test::max_difference(back, depth), 0);
}

TEST(Png, DepthIsBigEndianInTheFile) {
  cv::Mat depth(1, 1, CV_16UC1, cv::Scalar(0x0102));
  cv::Mat back;
  // Stored (compression 0), filtered with Sub: the only pixel's bytes follow the row's filter byte.
  const Bytes png = encoded(depth, PngPixels::kGrey16, 0);
  const Bytes sample{0x01, 0x02};
  EXPECT_NE(std::search(png.begin(), png.end(), sample.begin(), sample.end()), png.end());
  ASSERT_EQ(decode_png(png, PngPixels::kGrey16, back), "");
  EXPECT_EQ(back.at<std::uint16_t>(0, 0), 0x0102);
}

TEST(Png, RgbOrderIsTheFilesOrder) {
  const cv::Mat bgr = test::noise(CV_8UC3);
  cv::Mat rgb, back;
  ASSERT_EQ(decode_png(encoded(bgr, PngPixels::kBgr8), PngPixels::kRgb8, rgb), "");
  cv::Mat swapped(bgr.size(), CV_8UC3);
  const int from_to[] = {0, 2, 1, 1, 2, 0};
  cv::mixChannels(&bgr, 1, &swapped, 1, from_to, 3);
  EXPECT_EQ(test::max_difference(rgb, swapped), 0);
  ASSERT_EQ(decode_png(encoded(rgb, PngPixels::kRgb8), PngPixels::kBgr8, back), "");
  EXPECT_EQ(test::max_difference(back, bgr), 0);
}

TEST(Png, OpenCvReadsWhatWeWrite) {
  const cv::Mat bgr = test::noise(CV_8UC3), depth = test::noise(CV_16UC1);
  const cv::Mat colour_back = cv::imdecode(encoded(bgr, PngPixels::kBgr8), cv::IMREAD_UNCHANGED);
  const cv::Mat depth_back = cv::imdecode(encoded(depth, PngPixels::kGrey16), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(colour_back.type(), CV_8UC3);
  ASSERT_EQ(depth_back.type(), CV_16UC1);
  EXPECT_EQ(test::max_difference(colour_back, bgr), 0);
  EXPECT_EQ(test::max_difference(depth_back, depth), 0);
}

TEST(Png, WeReadWhatOpenCvWrites) {
  const cv::Mat bgr = test::noise(CV_8UC3), depth = test::noise(CV_16UC1);
  cv::Mat colour_back, depth_back;
  ASSERT_EQ(decode_png(opencv_png(bgr), PngPixels::kBgr8, colour_back), "");
  ASSERT_EQ(decode_png(opencv_png(depth), PngPixels::kGrey16, depth_back), "");
  EXPECT_EQ(test::max_difference(colour_back, bgr), 0);
  EXPECT_EQ(test::max_difference(depth_back, depth), 0);
}

// Grey, grey 16-bit, BGRA, 16-bit colour: read as colour exactly as cv::imread's IMREAD_COLOR reads them.
TEST(Png, AnyPngReadsAsColourAsOpenCvReadsIt) {
  for (const int type : {CV_8UC1, CV_16UC1, CV_8UC4, CV_16UC3}) {
    const Bytes png = opencv_png(test::noise(type));
    cv::Mat ours;
    ASSERT_EQ(decode_png(png, PngPixels::kBgr8, ours), "") << "type " << type;
    const cv::Mat theirs = cv::imdecode(png, cv::IMREAD_COLOR);
    ASSERT_EQ(ours.type(), theirs.type());
    EXPECT_EQ(test::max_difference(ours, theirs), 0) << "type " << type;
  }
}

TEST(Png, DepthMustBeSixteenBitGrey) {
  cv::Mat depth;
  const std::string bad = decode_png(opencv_png(test::noise(CV_8UC1)), PngPixels::kGrey16, depth);
  EXPECT_NE(bad.find("bit depth 8 with 1 channel(s), not 16-bit grey"), std::string::npos) << bad;
  EXPECT_TRUE(depth.empty()) << "refused from the header, before any allocation";
}

TEST(Png, HeaderGivesSizeDepthAndChannels) {
  ImageHeader header;
  ASSERT_EQ(read_png_header(opencv_png(test::noise(CV_16UC1, 5, 7)), header), "");
  EXPECT_EQ(header.width, 7);
  EXPECT_EQ(header.height, 5);
  EXPECT_EQ(header.bit_depth, 16);
  EXPECT_EQ(header.channels, 1);
}

TEST(Png, AnImageOfTheRightSizeIsDecodedIntoItsOwnBuffer) {
  const cv::Mat bgr = test::noise(CV_8UC3);
  cv::Mat image(bgr.size(), CV_8UC3, cv::Scalar::all(0));
  const auto* buffer = image.data;
  ASSERT_EQ(decode_png(encoded(bgr, PngPixels::kBgr8), PngPixels::kBgr8, image), "");
  EXPECT_EQ(image.data, buffer);
  EXPECT_EQ(test::max_difference(image, bgr), 0);
}

TEST(Png, AViewWithRowPaddingEncodes) {
  const cv::Mat big = test::noise(CV_16UC1, 48, 64);
  const cv::Mat view = big(cv::Rect(3, 2, 40, 30));
  cv::Mat back;
  ASSERT_EQ(decode_png(encoded(view, PngPixels::kGrey16), PngPixels::kGrey16, back), "");
  EXPECT_EQ(test::max_difference(back, view), 0);
}

TEST(Png, AnotherSizeThanExpectedIsRefusedFromTheHeader) {
  cv::Mat image;
  const std::string bad =
      decode_png(encoded(test::noise(CV_8UC3), PngPixels::kBgr8), PngPixels::kBgr8, image, {640, 480});
  EXPECT_EQ(bad, "PNG: image is 64x48, expected 640x480");
  EXPECT_TRUE(image.empty());
}

// A valid IHDR (its CRC right) claiming 100000 x 100000 pixels: refused from the header, before
// any allocation.
TEST(Png, AHugeClaimedSizeIsRefusedBeforeAllocating) {
  Bytes png = encoded(cv::Mat(1, 1, CV_8UC3, cv::Scalar::all(7)), PngPixels::kBgr8);
  for (const std::size_t at : {16u, 20u}) {  // IHDR width, height: 100000 big-endian
    png[at] = 0x00, png[at + 1] = 0x01, png[at + 2] = 0x86, png[at + 3] = 0xa0;
  }
  const auto crc = crc32(0, png.data() + 12, 17);  // the chunk's type and data
  for (int k = 0; k < 4; ++k) png[29 + std::size_t(k)] = std::uint8_t(crc >> (24 - 8 * k));
  cv::Mat image;
  EXPECT_EQ(decode_png(png, PngPixels::kBgr8, image),
            "PNG: Invalid IHDR data (libpng warned: Image height exceeds user limit in IHDR)");
  EXPECT_TRUE(image.empty());
}

TEST(Png, EveryTruncationIsAMessage) {
  const Bytes png = encoded(test::noise(CV_16UC1), PngPixels::kGrey16);
  for (std::size_t size = 0; size < png.size(); ++size) {
    cv::Mat depth;
    const std::string bad = decode_png({png.data(), size}, PngPixels::kGrey16, depth);
    ASSERT_EQ(bad.rfind("PNG: ", 0), 0u) << size << " of " << png.size() << " bytes: " << bad;
  }
}

TEST(Png, CorruptBytesAreAMessage) {
  const Bytes good = encoded(test::noise(CV_8UC3), PngPixels::kBgr8);
  cv::Mat image;
  Bytes flipped = good;
  flipped[good.size() / 2] ^= 0x55;  // inside IDAT: its CRC no longer matches
  EXPECT_NE(decode_png(flipped, PngPixels::kBgr8, image).find("CRC"), std::string::npos);
  EXPECT_EQ(decode_png(Bytes{'n', 'o', 't', ' ', 'a', ' ', 'p', 'n', 'g'}, PngPixels::kBgr8, image),
            "PNG: no PNG signature");
  EXPECT_EQ(decode_png(Bytes{}, PngPixels::kBgr8, image), "PNG: no PNG signature");
}

TEST(Png, EncodingRefusesWhatItCannotWrite) {
  Bytes png;
  EXPECT_NE(encode_png(cv::Mat(4, 4, CV_32FC1), PngPixels::kGrey16, 1, png).find("CV_16UC1"), std::string::npos);
  EXPECT_NE(encode_png(cv::Mat(4, 4, CV_16UC1), PngPixels::kBgr8, 1, png).find("CV_8UC3"), std::string::npos);
  EXPECT_NE(encode_png(cv::Mat(), PngPixels::kBgr8, 1, png).find("CV_8UC3"), std::string::npos);
  EXPECT_NE(encode_png(cv::Mat(4, 4, CV_8UC3), PngPixels::kBgr8, 10, png).find("0..9"), std::string::npos);
}

}  // namespace
}  // namespace cvo::image
