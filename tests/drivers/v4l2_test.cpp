// v4l2: the pixel conversions with known values, and opening without a camera (none is attached
// here): a missing node, a node that is not a V4L2 device, a spec without intrinsics.
#include <linux/videodev2.h>

#include <vector>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "drivers/v4l2_formats.hpp"

namespace cvo::drivers {
namespace {

using Bytes = std::vector<std::uint8_t>;

std::string open_error(const std::string& spec, const SourceOptions& options) {
  try {
    open_source(spec, options);
  } catch (const SourceError& e) {
    return e.what();
  }
  ADD_FAILURE() << spec << " opened";
  return {};
}

SourceOptions with_intrinsics() {
  SourceOptions o;
  o.intrinsics = core::Intrinsics{600, 600, 320, 240, 640, 480, 1000};
  return o;
}

TEST(V4l2Source, MissingNodeIsSourceErrorNamingIt) {
  const auto error = open_error("v4l2:/dev/cvo-test-no-video0,/dev/cvo-test-no-video1", with_intrinsics());
  EXPECT_NE(error.find("/dev/cvo-test-no-video0"), std::string::npos) << error;
  EXPECT_NE(error.find("no such device node"), std::string::npos) << error;
}

TEST(V4l2Source, NodeThatIsNotAVideoDeviceIsSourceError) {
  const auto error = open_error("v4l2:/dev/null,/dev/null", with_intrinsics());
  EXPECT_NE(error.find("not a V4L2 device"), std::string::npos) << error;
}

TEST(V4l2Source, NeedsIntrinsicsAndTwoNodes) {
  EXPECT_NE(open_error("v4l2:/dev/video0,/dev/video2", {}).find("v4l2 needs intrinsics (--camera ...)"),
            std::string::npos);
  for (const std::string spec : {"v4l2:/dev/video0", "v4l2:", "v4l2:/dev/video0,", "v4l2:a,b,c"})
    EXPECT_NE(open_error(spec, with_intrinsics()).find("COLOUR,DEPTH"), std::string::npos) << spec;
}

cv::Vec3b bgr_at(const cv::Mat& m, int x) { return m.at<cv::Vec3b>(0, x); }

void expect_near(const cv::Vec3b& got, const cv::Vec3b& want, int tolerance, const char* what) {
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], tolerance) << what << " channel " << c;
}

TEST(V4l2Formats, YuyvKnownColours) {
  // Y0 U Y1 V per pixel pair, BT.601 limited range: Y 16 black, 235 white, U = V = 128 grey axis.
  const Bytes yuyv{16,  128, 235, 128,   // black, white
                   81,  90,  81,  240,   // red (B G R = 0 0 255)
                   145, 54,  145, 34,    // green
                   41,  240, 41,  110};  // blue
  cv::Mat bgr;
  ASSERT_EQ(yuyv_to_bgr(yuyv, 8, 1, 16, bgr), "");
  ASSERT_EQ(bgr.type(), CV_8UC3);
  ASSERT_EQ(bgr.size(), cv::Size(8, 1));
  expect_near(bgr_at(bgr, 0), {0, 0, 0}, 2, "black");
  expect_near(bgr_at(bgr, 1), {255, 255, 255}, 2, "white");
  expect_near(bgr_at(bgr, 2), {0, 0, 255}, 4, "red");
  expect_near(bgr_at(bgr, 4), {0, 255, 0}, 4, "green");
  expect_near(bgr_at(bgr, 6), {255, 0, 0}, 4, "blue");
}

TEST(V4l2Formats, YuyvRowPaddingAndShortBuffers) {
  // 2x2 with rows padded to 8 bytes: the padding (0xee) must not show.
  const Bytes yuyv{235, 128, 235, 128, 0xee, 0xee, 0xee, 0xee, 16, 128, 16, 128};
  cv::Mat bgr;
  ASSERT_EQ(yuyv_to_bgr(yuyv, 2, 2, 8, bgr), "");
  expect_near(bgr.at<cv::Vec3b>(0, 1), {255, 255, 255}, 2, "row 0");
  expect_near(bgr.at<cv::Vec3b>(1, 0), {0, 0, 0}, 2, "row 1");
  EXPECT_NE(yuyv_to_bgr(Bytes(10), 2, 2, 8, bgr).find("too short"), std::string::npos);
  EXPECT_NE(yuyv_to_bgr(Bytes(64), 3, 2, 8, bgr).find("odd width"), std::string::npos);
  EXPECT_NE(yuyv_to_bgr(Bytes(64), 4, 2, 4, bgr).find("cannot hold"), std::string::npos);
}

TEST(V4l2Formats, Z16IsLittleEndianAndScaled) {
  const Bytes z16{0x34, 0x12, 0x00, 0x00, 0xff, 0xff, 0x01, 0x00};
  cv::Mat depth;
  ASSERT_EQ(z16_to_depth(z16, 4, 1, 8, 1.0, depth), "");
  ASSERT_EQ(depth.type(), CV_16UC1);
  EXPECT_EQ(depth.at<std::uint16_t>(0, 0), 0x1234);
  EXPECT_EQ(depth.at<std::uint16_t>(0, 1), 0) << "no measurement stays 0";
  EXPECT_EQ(depth.at<std::uint16_t>(0, 2), 65535);
  EXPECT_EQ(depth.at<std::uint16_t>(0, 3), 1);

  ASSERT_EQ(z16_to_depth(z16, 4, 1, 8, 2.5, depth), "");  // e.g. 2.5 mm units into 1 mm
  EXPECT_EQ(depth.at<std::uint16_t>(0, 0), 0x1234 * 5 / 2);
  EXPECT_EQ(depth.at<std::uint16_t>(0, 1), 0);
  EXPECT_EQ(depth.at<std::uint16_t>(0, 2), 65535) << "saturates";
  EXPECT_EQ(depth.at<std::uint16_t>(0, 3), 2) << "2.5 rounds to even";

  const Bytes padded{1, 0, 0xee, 0xee, 2, 0};  // 1x2, rows of 4 bytes
  ASSERT_EQ(z16_to_depth(padded, 1, 2, 4, 1.0, depth), "");
  EXPECT_EQ(depth.at<std::uint16_t>(0, 0), 1);
  EXPECT_EQ(depth.at<std::uint16_t>(1, 0), 2);
  EXPECT_NE(z16_to_depth(Bytes(5), 1, 2, 4, 1.0, depth).find("too short"), std::string::npos);
  EXPECT_NE(z16_to_depth(padded, 1, 2, 4, 0.0, depth).find("scale"), std::string::npos);
}

TEST(V4l2Formats, MjpegDecodesAndChecksItsSize) {
  cv::Mat image(48, 64, CV_8UC3);
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c) image.at<cv::Vec3b>(r, c) = cv::Vec3b(uchar(4 * c), uchar(5 * r), 128);
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 98}));

  cv::Mat bgr;
  ASSERT_EQ(mjpeg_to_bgr(jpeg, 64, 48, bgr), "");
  EXPECT_LT(cv::norm(bgr, image, cv::NORM_L1) / (image.total() * 3.0), 3.0);
  EXPECT_NE(mjpeg_to_bgr(jpeg, 640, 480, bgr).find("64x48"), std::string::npos);
  EXPECT_NE(mjpeg_to_bgr(Bytes{0xff, 0xd8, 1, 2, 3}, 64, 48, bgr).find("does not decode"), std::string::npos);
  EXPECT_NE(mjpeg_to_bgr(Bytes{}, 64, 48, bgr).find("empty"), std::string::npos);
}

// UVC cameras send MJPEG frames without Huffman tables (DHT); the decoder must assume the standard ones.
TEST(V4l2Formats, MjpegWithoutHuffmanTablesDecodes) {
  cv::Mat image(16, 16, CV_8UC3, cv::Scalar(40, 120, 200));
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  Bytes stripped{jpeg[0], jpeg[1]};
  std::size_t i = 2;
  int removed = 0;
  while (i + 4 <= jpeg.size() && jpeg[i] == 0xff && jpeg[i + 1] != 0xda) {  // markers up to start of scan
    const std::size_t length = 2 + (std::size_t(jpeg[i + 2]) << 8 | jpeg[i + 3]);
    if (jpeg[i + 1] == 0xc4) {
      ++removed;
    } else {
      stripped.insert(stripped.end(), jpeg.begin() + std::ptrdiff_t(i), jpeg.begin() + std::ptrdiff_t(i + length));
    }
    i += length;
  }
  stripped.insert(stripped.end(), jpeg.begin() + std::ptrdiff_t(i), jpeg.end());
  ASSERT_GT(removed, 0);

  cv::Mat bgr;
  ASSERT_EQ(mjpeg_to_bgr(stripped, 16, 16, bgr), "");
  EXPECT_LT(cv::norm(bgr, image, cv::NORM_INF), 6.0);
}

TEST(V4l2Formats, FourccText) {
  EXPECT_EQ(fourcc_text(V4L2_PIX_FMT_Z16), "Z16 ");
  EXPECT_EQ(fourcc_text(V4L2_PIX_FMT_YUYV), "YUYV");
  EXPECT_EQ(fourcc_text(V4L2_PIX_FMT_MJPEG), "MJPG");
}

}  // namespace
}  // namespace cvo::drivers
