// Every channel type survives encode -> decode unchanged, and wire_layout.cpp's table of count
// offsets matches what lcm-gen actually encodes.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

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
struct Sample<cvo_lcm::keyframe_chunk_t> {
  static auto make() { return test::sample_keyframe_chunk(); }
};

template <>
struct Sample<cvo_lcm::grid_t> {
  static auto make() { return test::sample_grid(); }
};

template <class T>
class MessageRoundTrip : public ::testing::Test {};
using ChannelTypes =
    ::testing::Types<cvo_lcm::rgbd_frame_t, cvo_lcm::pose_t, cvo_lcm::keyframe_t, cvo_lcm::local_graph_t,
                     cvo_lcm::map_t, cvo_lcm::map_correction_t, cvo_lcm::status_t, cvo_lcm::keyframe_request_t,
                     cvo_lcm::keyframe_chunk_t, cvo_lcm::grid_t>;
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

std::int32_t be32(const std::uint8_t* p) { return (p[0] << 24) | (p[1] << 16) | (p[2] << 8) | p[3]; }

// Where the table puts each string's length in the sample's encoding (body offsets).
std::vector<std::int64_t> string_offsets(const WireLayout& layout, const std::uint8_t* body) {
  std::int64_t size = layout.header_bytes;
  std::int64_t strings = layout.num_strings;
  for (std::size_t i = 0; i < layout.counts.size(); ++i) {
    const std::int32_t count = be32(body + layout.counts[i].offset);
    size += std::int64_t{count} * layout.counts[i].bytes_per_element;
    if (static_cast<int>(i) == layout.strings_counted_by) strings += count;
  }
  std::vector<std::int64_t> at;
  if (layout.strings_at >= 0) size = layout.strings_at;
  for (std::int64_t i = 0; i < strings; ++i, size += 4 + be32(body + size)) at.push_back(size);
  at.push_back(size);  // the end of the last: where auth_t begins
  return at;
}

TYPED_TEST(MessageRoundTrip, WireLayoutTableMatchesTheEncoding) {
  const TypeParam m = Sample<TypeParam>::make();
  const auto bytes = encode(m);
  const WireLayout layout = wire_layout(TypeParam::getTypeName());
  const std::uint8_t* body = bytes.data() + 8;
  for (const auto& field : layout.counts)
    EXPECT_GT(be32(body + field.offset), 0) << field.name << ": the sample sets every count";
  const auto at = string_offsets(layout, body);
  for (std::size_t i = 0; i + 1 < at.size(); ++i) {  // each length is a text's, with its one NUL
    const std::int32_t length = be32(body + at[i]);
    ASSERT_GE(length, 1) << "string " << i;
    EXPECT_EQ(body[at[i] + 4 + length - 1], 0) << "string " << i;
  }
  // Then auth_t, the last field of every type sent on a channel: the last kAuthTrailerBytes.
  EXPECT_EQ(at.back() + kAuthTrailerBytes, static_cast<std::int64_t>(bytes.size()) - 8)
      << "header and element sizes of the table, its strings, then the auth trailer";
}

TYPED_TEST(MessageRoundTrip, EveryStringsCorruptLengthIsRefusedBeforeDecoding) {
  const auto bytes = encode(Sample<TypeParam>::make());
  const WireLayout layout = wire_layout(TypeParam::getTypeName());
  const auto at = string_offsets(layout, bytes.data() + 8);
  if (at.size() < 2) GTEST_SKIP() << TypeParam::getTypeName() << " has no strings";
  for (std::size_t i = 0; i + 1 < at.size(); ++i)
    for (const std::uint8_t high : {std::uint8_t{0x7f}, std::uint8_t{0x80}}) {  // huge, negative
      auto corrupt = bytes;
      corrupt[8 + static_cast<std::size_t>(at[i])] = high;
      std::string error;
      EXPECT_FALSE(decode<TypeParam>(corrupt.data(), static_cast<int>(corrupt.size()), &error));
      EXPECT_NE(error.find("corrupt string length"), std::string::npos) << "string " << i << ": " << error;
    }
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
