// RgbdFrame <-> rgbd_frame_t for every encoding: raw and PNG bit-exact, JPEG close; bad messages
// and bad frames refused with a message.
#include <chrono>
#include <cstdio>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "tests/lcm/image_bombs.hpp"

namespace cvo::lcm {
namespace {

using core::BadKind;

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
  m.depth.resize(100);  // a sound header, then the data ends: the decoder runs and fails
  m.depth_size = 100;
  BadKind kind = BadKind::kBody;
  EXPECT_FALSE(from_message(m, &error, &kind));
  EXPECT_NE(error.find("depth image does not decode"), std::string::npos) << error;
  EXPECT_EQ(kind, BadKind::kContent);

  m.depth[20] ^= 0xff;  // the IHDR's height: refused before any decoder runs
  EXPECT_FALSE(from_message(m, &error, &kind));
  EXPECT_NE(error.find("depth image: PNG header says 640x"), std::string::npos) << error;
  EXPECT_EQ(kind, BadKind::kImageSize);

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

// Decompression bombs and images of another format than declared: each refused by its kind from
// the header alone, before a decoder could allocate the 16384x16384 image its header claims (805 MB
// of colour) or a decoder of another format could run.
TEST(RgbdConversion, BombsAndMislabelledImagesAreRefusedBeforeDecoding) {
  const auto frame = tum_frame();
  std::string error;
  const auto png = to_message(frame, {.colour = ColourEncoding::kPng, .depth = DepthEncoding::kPng}, &error);
  ASSERT_TRUE(png) << error;
  const auto jpeg = to_message(frame, {.colour = ColourEncoding::kJpeg, .depth = DepthEncoding::kPng}, &error);
  ASSERT_TRUE(jpeg) << error;
  struct Case {
    const char* name;
    cvo_lcm::rgbd_frame_t message;
    BadKind kind;
    const char* says;
  };
  const auto with_colour = [](cvo_lcm::rgbd_frame_t m, std::vector<std::uint8_t> colour) {
    m.colour = std::move(colour);
    m.colour_size = static_cast<std::int32_t>(m.colour.size());
    return m;
  };
  auto depth_bomb = *png;
  depth_bomb.depth = test::png_bomb(16384, 16384, true);
  depth_bomb.depth_size = static_cast<std::int32_t>(depth_bomb.depth.size());
  const std::vector<Case> cases = {
      {"PNG bomb", with_colour(*png, test::png_bomb(16384, 16384, false)), BadKind::kImageSize,
       "PNG header says 16384x16384"},
      {"JPEG bomb", with_colour(*jpeg, test::jpeg_bomb(16384, 16384)), BadKind::kImageSize,
       "JPEG header says 16384x16384"},
      {"depth PNG bomb", depth_bomb, BadKind::kImageSize, "depth image: PNG header says 16384x16384"},
      {"PNG labelled JPEG", with_colour(*jpeg, png->colour), BadKind::kImageFormat, "not a JPEG"},
      {"JPEG labelled PNG", with_colour(*png, jpeg->colour), BadKind::kImageFormat, "not a PNG"},
      {"HDR labelled PNG", with_colour(*png, test::hdr_file(640, 480)), BadKind::kImageFormat, "not a PNG"},
      {"HDR labelled JPEG", with_colour(*jpeg, test::hdr_file(640, 480)), BadKind::kImageFormat, "not a JPEG"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    BadKind kind = BadKind::kContent;
    const auto start = std::chrono::steady_clock::now();
    EXPECT_FALSE(from_message(c.message, &error, &kind));
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    std::printf("%-18s %8zu bytes refused in %7.1f us: %s\n", c.name, c.message.colour.size() + c.message.depth.size(),
                us, error.c_str());
    EXPECT_EQ(kind, c.kind);
    EXPECT_NE(error.find(c.says), std::string::npos) << error;
  }
  // The bombs are real: their data inflates to the size the header claims.
  const auto bomb = test::png_bomb(64, 32, false);
  cv::Mat decoded = cv::imdecode(bomb, cv::IMREAD_COLOR);
  EXPECT_EQ(decoded.cols, 64);
  EXPECT_EQ(decoded.rows, 32);
  EXPECT_EQ(cv::imdecode(test::jpeg_bomb(64, 32), cv::IMREAD_COLOR).cols, 64);
}

// What each header check looks at: the message's size, 8-bit colour or 16-bit grey depth, PNG's
// IHDR first, JPEG's frame header before its scan, and the encoded size.
TEST(RgbdConversion, ImageHeadersAreCheckedAgainstTheMessage) {
  const auto frame = tum_frame();
  std::vector<std::uint8_t> colour_png, depth_png, colour_jpeg;
  ASSERT_TRUE(cv::imencode(".png", frame.bgr, colour_png));
  ASSERT_TRUE(cv::imencode(".png", frame.depth, depth_png));
  ASSERT_TRUE(cv::imencode(".jpg", frame.bgr, colour_jpeg));
  const ExpectedImage colour{ImageFormat::kPng, 640, 480, false}, depth{ImageFormat::kPng, 640, 480, true};
  const ExpectedImage jpeg{ImageFormat::kJpeg, 640, 480, false};
  const auto check = [](const std::vector<std::uint8_t>& bytes, const ExpectedImage& e) {
    BadKind kind = BadKind::kContent;
    const std::string bad = check_image_header(bytes.data(), bytes.size(), e, &kind);
    return bad.empty() ? std::string("ok") : std::string(to_string(kind)) + ": " + bad;
  };
  EXPECT_EQ(check(colour_png, colour), "ok");
  EXPECT_EQ(check(depth_png, depth), "ok");
  EXPECT_EQ(check(colour_jpeg, jpeg), "ok");
  EXPECT_NE(check(depth_png, colour).find("image size: PNG of bit depth 16"), std::string::npos);
  EXPECT_NE(check(colour_png, depth).find("image size: PNG of bit depth 8"), std::string::npos);
  EXPECT_NE(check(colour_png, {ImageFormat::kPng, 320, 480, false}).find("image size: PNG header says 640x480"),
            std::string::npos);
  EXPECT_NE(check(colour_jpeg, {ImageFormat::kJpeg, 640, 240, false}).find("image size: JPEG header says 640x480"),
            std::string::npos);
  std::vector<std::uint8_t> padded(70000, 0);  // a JPEG start, then more than an 8x6 image can take
  padded[0] = 0xff;
  padded[1] = 0xd8;
  padded[2] = 0xff;
  EXPECT_NE(check(padded, {ImageFormat::kJpeg, 8, 6, false}).find("image size: 70000 bytes, more than"),
            std::string::npos);

  auto no_ihdr = colour_png;
  no_ihdr[12] = 'X';
  EXPECT_NE(check(no_ihdr, colour).find("image format: PNG without an IHDR"), std::string::npos);
  // A JPEG cut before its frame header, and one whose first segment's length runs off the end.
  EXPECT_NE(
      check({colour_jpeg.begin(), colour_jpeg.begin() + 20}, jpeg).find("image format: JPEG without a frame header"),
      std::string::npos);
  auto no_sof = colour_jpeg;
  for (std::size_t i = 2; i + 1 < no_sof.size(); ++i)
    if (no_sof[i] == 0xff && no_sof[i + 1] == 0xc0) no_sof[i + 1] = 0xe5;  // the frame header becomes an APP5 segment
  EXPECT_NE(check(no_sof, jpeg).find("image format: JPEG without a frame header"), std::string::npos);
  EXPECT_NE(check({}, jpeg).find("content: empty"), std::string::npos);
}

TEST(RgbdConversion, EncodingNames) {
  EXPECT_EQ(parse_colour_encoding("jpeg"), ColourEncoding::kJpeg);
  EXPECT_EQ(parse_depth_encoding("raw"), DepthEncoding::kRawU16Le);
  EXPECT_FALSE(parse_colour_encoding("webp"));
  EXPECT_STREQ(to_string(ColourEncoding::kRawBgr8), "raw");
}

// A JPEG whose scan is cut short keeps a sound header, so it reaches the decoder; libjpeg would fill
// the missing rows with grey (cv::imdecode returned that image), and the frame is refused instead.
TEST(RgbdConversion, JpegWithATruncatedScanIsRefused) {
  std::string error;
  auto m = to_message(tum_frame(), {.colour = ColourEncoding::kJpeg, .depth = DepthEncoding::kPng}, &error);
  ASSERT_TRUE(m) << error;
  m->colour.resize(m->colour.size() / 2);
  m->colour_size = static_cast<std::int32_t>(m->colour.size());
  BadKind kind = BadKind::kBody;
  EXPECT_FALSE(from_message(*m, &error, &kind));
  EXPECT_NE(error.find("colour image does not decode to 8-bit colour of 640x480: JPEG: Premature end of JPEG file"),
            std::string::npos)
      << error;
  EXPECT_EQ(kind, BadKind::kContent);
}

}  // namespace
}  // namespace cvo::lcm
