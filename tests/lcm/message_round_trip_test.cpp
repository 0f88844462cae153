// Every channel type survives encode -> decode unchanged, and wire_layout.cpp's table of count
// offsets matches what lcm-gen actually encodes.
#include <gtest/gtest.h>

#include "lcm/sample_messages.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/wire_layout.hpp"

namespace cvo::lcm {
namespace {

template <class T>
struct Sample;
template <>
struct Sample<cvo_lcm::rgbd_frame_t> {
  static auto make() { return test::sample_rgbd(); }
};
template <>
struct Sample<cvo_lcm::pose_t> {
  static auto make() { return test::sample_pose_message(); }
};
template <>
struct Sample<cvo_lcm::keyframe_t> {
  static auto make() { return test::sample_keyframe(); }
};
template <>
struct Sample<cvo_lcm::local_graph_t> {
  static auto make() { return test::sample_local_graph(); }
};
template <>
struct Sample<cvo_lcm::map_t> {
  static auto make() { return test::sample_map(); }
};
template <>
struct Sample<cvo_lcm::map_correction_t> {
  static auto make() { return test::sample_map_correction(); }
};
template <>
struct Sample<cvo_lcm::status_t> {
  static auto make() { return test::sample_status(); }
};
template <>
struct Sample<cvo_lcm::keyframe_request_t> {
  static auto make() { return test::sample_keyframe_request(); }
};

template <>
struct Sample<cvo_lcm::grid_t> {
  static auto make() { return test::sample_grid(); }
};

template <class T>
class MessageRoundTrip : public ::testing::Test {};
using ChannelTypes = ::testing::Types<cvo_lcm::rgbd_frame_t, cvo_lcm::pose_t, cvo_lcm::keyframe_t,
                                      cvo_lcm::local_graph_t, cvo_lcm::map_t, cvo_lcm::map_correction_t,
                                      cvo_lcm::status_t, cvo_lcm::keyframe_request_t, cvo_lcm::grid_t>;
TYPED_TEST_SUITE(MessageRoundTrip, ChannelTypes);

TYPED_TEST(MessageRoundTrip, DecodesToTheSameMessage) {
  const TypeParam original = Sample<TypeParam>::make();
  const auto bytes = encode(original);
  std::string error;
  const auto decoded = decode<TypeParam>(bytes.data(), static_cast<int>(bytes.size()), &error);
  ASSERT_TRUE(decoded) << error;
  // The encoding covers every field, so equal encodings mean equal messages.
  EXPECT_EQ(encode(*decoded), bytes);
}

TYPED_TEST(MessageRoundTrip, WireLayoutTableMatchesTheEncoding) {
  const TypeParam m = Sample<TypeParam>::make();
  const auto bytes = encode(m);
  const WireLayout layout = wire_layout(TypeParam::getTypeName());
  if (layout.strings_at >= 0) {  // the first string's length is where the table says
    const auto* at = bytes.data() + 8 + layout.strings_at;
    EXPECT_EQ((at[0] << 24) | (at[1] << 16) | (at[2] << 8) | at[3], 13) << "\"cvo-trackerd\" and its NUL";
  }
  if (layout.counts.empty()) GTEST_SKIP() << TypeParam::getTypeName() << " has no variable-length arrays";
  const std::uint8_t* body = bytes.data() + 8;
  std::int64_t size = layout.header_bytes;
  for (const auto& field : layout.counts) {
    const std::int32_t count = (body[field.offset] << 24) | (body[field.offset + 1] << 16) |
                               (body[field.offset + 2] << 8) | body[field.offset + 3];
    EXPECT_GT(count, 0) << field.name << ": the sample sets every count";
    size += std::int64_t{count} * field.bytes_per_element;
  }
  if (layout.strings_at == kStringsAfterArrays)  // grid_t's frame: its length, "grid" and its NUL
    for (int i = 0; i < layout.num_strings; ++i)
      size += 4 + ((body[size] << 24) | (body[size + 1] << 16) | (body[size + 2] << 8) | body[size + 3]);
  // Then auth_t, the last field of every type sent on a channel: the last kAuthTrailerBytes.
  EXPECT_EQ(size + kAuthTrailerBytes, static_cast<std::int64_t>(bytes.size()) - 8)
      << "header and element sizes of the table, then the auth trailer";
}

TEST(MessageRoundTrip, SpotChecksOfDecodedFields) {
  const auto bytes = encode(test::sample_status());
  const auto status = decode<cvo_lcm::status_t>(bytes.data(), static_cast<int>(bytes.size()), nullptr);
  ASSERT_TRUE(status);
  EXPECT_EQ(status->process, "cvo-trackerd");
  EXPECT_EQ(status->robot, "robot-7");
  EXPECT_EQ(status->bad_messages[cvo_lcm::status_t::BAD_FINGERPRINT], 11);
  const auto kf_bytes = encode(test::sample_keyframe());
  const auto kf = decode<cvo_lcm::keyframe_t>(kf_bytes.data(), static_cast<int>(kf_bytes.size()), nullptr);
  ASSERT_TRUE(kf);
  ASSERT_EQ(kf->labels.size(), 3u);
  EXPECT_FLOAT_EQ(kf->labels[2][2], 2.3f);
  EXPECT_EQ(kf->pose.orientation[0], 0.5);
}

}  // namespace
}  // namespace cvo::lcm
