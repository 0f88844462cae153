// RgbdFrame <-> rgbd_frame_t for every encoding: raw and PNG bit-exact, JPEG close; bad messages
// and bad frames refused with a message.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

namespace cvo::lcm {
namespace {

core::RgbdFrame tum_frame() {
  return io::TumSequence::open(std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50").read(3);
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// Encodes, sends through bytes, decodes: what a subscriber sees.
core::RgbdFrame through_the_wire(const core::RgbdFrame& frame, const RgbdEncoding& encoding) {
  std::string error;
  const auto message = to_message(frame, encoding, &error);
  EXPECT_TRUE(message) << error;
  const auto bytes = encode(*message);
  const auto decoded = decode<cvo_lcm::rgbd_frame_t>(bytes.data(), static_cast<int>(bytes.size()), &error);
  EXPECT_TRUE(decoded) << error;
  const auto back = from_message(*decoded, &error);
  EXPECT_TRUE(back) << error;
  return back.value_or(core::RgbdFrame{});
}

void expect_same_metadata(const core::RgbdFrame& a, const core::RgbdFrame& b) {
  EXPECT_EQ(a.index, b.index);
  EXPECT_EQ(a.timestamp, b.timestamp);
  EXPECT_EQ(a.depth_timestamp, b.depth_timestamp);
  EXPECT_EQ(a.intrinsics.fx, b.intrinsics.fx);
  EXPECT_EQ(a.intrinsics.cy, b.intrinsics.cy);
  EXPECT_EQ(a.intrinsics.width, b.intrinsics.width);
  EXPECT_EQ(a.intrinsics.depth_scale, b.intrinsics.depth_scale);
  EXPECT_EQ(a.intrinsics.distortion, b.intrinsics.distortion);
}

TEST(RgbdConversion, LosslessEncodingsAreExact) {
  const auto frame = tum_frame();
  ASSERT_TRUE(frame.intrinsics.has_distortion()) << "tum_fr1: the lens coefficients must travel too";
  for (auto colour : {ColourEncoding::kRawBgr8, ColourEncoding::kPng})
    for (auto depth : {DepthEncoding::kRawU16Le, DepthEncoding::kPng}) {
      SCOPED_TRACE(std::string(to_string(colour)) + "/" + to_string(depth));
      const auto back = through_the_wire(frame, {.colour = colour, .depth = depth});
      expect_same_metadata(frame, back);
      EXPECT_TRUE(identical(back.bgr, frame.bgr));
      EXPECT_TRUE(identical(back.depth, frame.depth));
    }
}

TEST(RgbdConversion, JpegIsClose) {
  const auto frame = tum_frame();
  const auto back = through_the_wire(frame, {.colour = ColourEncoding::kJpeg, .depth = DepthEncoding::kPng});
  ASSERT_EQ(back.bgr.type(), CV_8UC3);
  ASSERT_EQ(back.bgr.size(), frame.bgr.size());
  const double mean_abs = cv::norm(back.bgr, frame.bgr, cv::NORM_L1) / static_cast<double>(frame.bgr.total() * 3);
  EXPECT_LT(mean_abs, 4.0) << "quality 90";
  EXPECT_TRUE(identical(back.depth, frame.depth)) << "depth is never lossy";
}

TEST(RgbdConversion, RawDepthIsLittleEndian) {
  core::RgbdFrame f;
  f.intrinsics = {500, 500, 1, 0.5, 2, 1, 5000};
  f.bgr = cv::Mat(1, 2, CV_8UC3, cv::Scalar(1, 2, 3));
  f.depth = (cv::Mat_<std::uint16_t>(1, 2) << 0x1234, 0xabcd);
  std::string error;
  const auto m = to_message(f, {.colour = ColourEncoding::kRawBgr8, .depth = DepthEncoding::kRawU16Le}, &error);
  ASSERT_TRUE(m) << error;
  EXPECT_EQ(m->depth, (std::vector<std::uint8_t>{0x34, 0x12, 0xcd, 0xab}));
  EXPECT_EQ(m->colour, (std::vector<std::uint8_t>{1, 2, 3, 1, 2, 3}));
}

TEST(RgbdConversion, BadFramesAreRefused) {
  auto frame = tum_frame();
  std::string error;
  auto bad = frame;
  bad.depth = cv::Mat(10, 10, CV_16UC1);
  EXPECT_FALSE(to_message(bad, {}, &error));
  EXPECT_NE(error.find("depth image must be CV_16UC1 640x480"), std::string::npos) << error;
  bad = frame;
  bad.intrinsics.fx = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(to_message(bad, {}, &error));
  EXPECT_NE(error.find("fx"), std::string::npos) << error;
}

TEST(RgbdConversion, BadMessagesAreRefused) {
  const auto frame = tum_frame();
  std::string error;
  const auto good = to_message(frame, {.colour = ColourEncoding::kRawBgr8, .depth = DepthEncoding::kPng}, &error);
  ASSERT_TRUE(good) << error;

  auto m = *good;
  m.colour.pop_back();
  m.colour_size -= 1;
  EXPECT_FALSE(from_message(m, &error));
  EXPECT_NE(error.find("raw colour needs 921600 bytes"), std::string::npos) << error;

  m = *good;
  m.depth[20] ^= 0xff;  // inside the PNG header: does not decode
  m.depth.resize(100);
  m.depth_size = 100;
  EXPECT_FALSE(from_message(m, &error));
  EXPECT_NE(error.find("depth image does not decode"), std::string::npos) << error;

  m = *good;
  m.width = 320;  // the images no longer match
  m.colour_encoding = cvo_lcm::rgbd_frame_t::COLOUR_PNG;
  EXPECT_FALSE(from_message(m, &error));

  m = *good;
  m.colour_encoding = 9;
  EXPECT_FALSE(from_message(m, &error));
  EXPECT_NE(error.find("unknown colour encoding 9"), std::string::npos) << error;

  m = *good;
  m.fy = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(from_message(m, &error));
  EXPECT_NE(error.find("intrinsics: fy"), std::string::npos) << error;

  m = *good;
  m.frame_index = -1;
  EXPECT_FALSE(from_message(m, &error));
}

TEST(RgbdConversion, EncodingNames) {
  EXPECT_EQ(parse_colour_encoding("jpeg"), ColourEncoding::kJpeg);
  EXPECT_EQ(parse_depth_encoding("raw"), DepthEncoding::kRawU16Le);
  EXPECT_FALSE(parse_colour_encoding("webp"));
  EXPECT_STREQ(to_string(ColourEncoding::kRawBgr8), "raw");
}

}  // namespace
}  // namespace cvo::lcm
