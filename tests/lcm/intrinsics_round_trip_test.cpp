// core::Intrinsics survives every trip it makes whole: through CVO_RGBD (rgbd_frame_t), through
// CVO_KEYFRAME (keyframe_t), both over their wire bytes, and through a camera file.
//
// What guards a field added later: every_field_set() names all the fields of Intrinsics in one
// structured binding, which stops compiling when a field is added; whoever adds it must give it a
// value unlike its default here, and then each trip below, compared with Intrinsics' defaulted ==
// (every field), fails until it carries the new field.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "libcvo/core/camera.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "tests/lcm/through_bytes.hpp"

namespace cvo::lcm {
namespace {

// A valid camera whose every field differs from its default (and the presets'), so a field lost
// on the way comes back as its default and the comparison sees it.
core::Intrinsics every_field_set() {
  core::Intrinsics k;
  auto& [fx, fy, cx, cy, width, height, depth_scale, distortion, readout_s] = k;
  fx = 401.25;
  fy = 402.5;
  cx = 31.75;
  cy = 23.125;
  width = 64;
  height = 48;
  depth_scale = 1000.0;
  distortion = {0.125, -0.25, 0.001953125, -0.0009765625, 0.0625};
  readout_s = 0.0234375;
  return k;
}

TEST(IntrinsicsRoundTrip, TheSampleCameraSetsEveryFieldAwayFromItsDefault) {
  const core::Intrinsics k = every_field_set();
  ASSERT_EQ(k.validate(), "");
  const core::Intrinsics d{};
  const auto& [fx, fy, cx, cy, width, height, depth_scale, distortion, readout_s] = k;
  const auto& [dfx, dfy, dcx, dcy, dwidth, dheight, ddepth_scale, ddistortion, dreadout_s] = d;
  EXPECT_NE(fx, dfx);
  EXPECT_NE(fy, dfy);
  EXPECT_NE(cx, dcx);
  EXPECT_NE(cy, dcy);
  EXPECT_NE(width, dwidth);
  EXPECT_NE(height, dheight);
  EXPECT_NE(depth_scale, ddepth_scale);
  for (std::size_t i = 0; i < distortion.size(); ++i) EXPECT_NE(distortion[i], ddistortion[i]) << "coefficient " << i;
  EXPECT_NE(readout_s, dreadout_s);
}

TEST(IntrinsicsRoundTrip, EqualityComparesEveryField) {
  const core::Intrinsics k = every_field_set();
  EXPECT_EQ(k, every_field_set());
  auto other = k;
  other.readout_s = 0;
  EXPECT_NE(other, k) << "a global shutter is another camera than a rolling one";
  other = k;
  other.distortion[4] = 0;
  EXPECT_NE(other, k);
  other = k;
  other.depth_scale = 5000;
  EXPECT_NE(other, k);
}

core::RgbdFrame frame_of(const core::Intrinsics& k) {
  core::RgbdFrame frame;
  frame.index = 3;
  frame.timestamp = 1305031102.175304;
  frame.depth_timestamp = 1305031102.160407;
  frame.intrinsics = k;
  frame.bgr = cv::Mat(k.height, k.width, CV_8UC3, cv::Scalar(10, 20, 30));
  frame.depth = cv::Mat(k.height, k.width, CV_16UC1, cv::Scalar(5000));
  return frame;
}

TEST(IntrinsicsRoundTrip, ThroughCvoRgbdEveryFieldComesBack) {
  const core::Intrinsics k = every_field_set();
  std::string error;
  const auto message =
      to_message(frame_of(k), RgbdEncoding{ColourEncoding::kRawBgr8, DepthEncoding::kRawU16Le}, &error);
  ASSERT_TRUE(message) << error;
  const auto decoded = through_bytes(*message);
  ASSERT_TRUE(decoded);
  const auto back = from_message(*decoded, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->intrinsics, k);
}

TEST(IntrinsicsRoundTrip, ThroughCvoKeyframeEveryFieldComesBack) {
  const core::Intrinsics k = every_field_set();
  Keyframe keyframe{7, 2, frame_of(k), core::SE3{}, registration::PointCloud(1), "hall-a"};
  keyframe.cloud.push_back({0.5f, -0.25f, 1.5f}, registration::Feature{});
  std::string error;
  const auto message = to_message(keyframe, RgbdEncoding{ColourEncoding::kPng, DepthEncoding::kPng}, &error);
  ASSERT_TRUE(message) << error;
  const auto decoded = through_bytes(*message);
  ASSERT_TRUE(decoded);
  const auto back = from_message(*decoded, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->frame.intrinsics, k);
}

TEST(IntrinsicsRoundTrip, ThroughACameraFileEveryFieldComesBack) {
  const core::Intrinsics k = every_field_set();
  EXPECT_EQ(io::parse_intrinsics(io::format_intrinsics_yaml(k, "round trip"), "camera.yaml"), k);
}

}  // namespace
}  // namespace cvo::lcm
