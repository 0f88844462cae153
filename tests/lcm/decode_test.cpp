// decode() on hostile input: short, truncated, oversized, wrong fingerprint, corrupt counts and
// random garbage all give nullopt and a message, never a crash, an exception or a huge allocation.
#include <random>

#include <gtest/gtest.h>

#include "lcm/sample_messages.hpp"
#include "libcvo/lcm/decode.hpp"

namespace cvo::lcm {
namespace {

template <class T>
void expect_every_truncation_fails(const T& message) {
  const auto bytes = encode(message);
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    std::string error;
    const auto decoded = decode<T>(bytes.data(), static_cast<int>(n), &error);
    EXPECT_FALSE(decoded) << T::getTypeName() << " cut to " << n << " bytes";
    EXPECT_NE(error.find(T::getTypeName()), std::string::npos) << error;
  }
}

TEST(Decode, EveryTruncationOfEveryTypeFails) {
  expect_every_truncation_fails(test::sample_rgbd());
  expect_every_truncation_fails(test::sample_pose_message());
  expect_every_truncation_fails(test::sample_keyframe());
  expect_every_truncation_fails(test::sample_local_graph());
  expect_every_truncation_fails(test::sample_map());
  expect_every_truncation_fails(test::sample_map_correction());
  expect_every_truncation_fails(test::sample_status());
  expect_every_truncation_fails(test::sample_keyframe_request());
  expect_every_truncation_fails(test::sample_keyframe_chunk());
  expect_every_truncation_fails(test::sample_grid());
}

TEST(Decode, ShortBufferSaysSo) {
  const std::uint8_t bytes[4] = {1, 2, 3, 4};
  std::string error;
  EXPECT_FALSE(decode<cvo_lcm::pose_t>(bytes, 4, &error));
  EXPECT_NE(error.find("shorter than the 8-byte fingerprint"), std::string::npos) << error;
  EXPECT_FALSE(decode<cvo_lcm::pose_t>(nullptr, 100, &error));
  EXPECT_FALSE(decode<cvo_lcm::pose_t>(bytes, -1, &error));
}

TEST(Decode, AnotherTypeIsAWrongFingerprint) {
  const auto bytes = encode(test::sample_pose_message());
  std::string error;
  EXPECT_FALSE(decode<cvo_lcm::status_t>(bytes.data(), static_cast<int>(bytes.size()), &error));
  EXPECT_NE(error.find("wrong fingerprint"), std::string::npos) << error;
  EXPECT_NE(error.find("cvo_lcm.status_t"), std::string::npos) << error;
}

TEST(Decode, OneFlippedFingerprintBitIsRejected) {
  auto bytes = encode(test::sample_rgbd());
  bytes[3] ^= 0x10;
  std::string error;
  EXPECT_FALSE(decode<cvo_lcm::rgbd_frame_t>(bytes.data(), static_cast<int>(bytes.size()), &error));
  EXPECT_NE(error.find("wrong fingerprint"), std::string::npos) << error;
}

TEST(Decode, TrailingBytesAreRejected) {
  auto bytes = encode(test::sample_map());
  bytes.push_back(0);
  std::string error;
  EXPECT_FALSE(decode<cvo_lcm::map_t>(bytes.data(), static_cast<int>(bytes.size()), &error));
  EXPECT_NE(error.find("1 trailing bytes"), std::string::npos) << error;
}

TEST(Decode, AnotherSchemaVersionIsRejected) {
  auto message = test::sample_pose_message();
  message.version = 1;  // an old tracker, before sessions
  const auto bytes = encode(message);
  std::string error;
  EXPECT_FALSE(decode<cvo_lcm::pose_t>(bytes.data(), static_cast<int>(bytes.size()), &error));
  EXPECT_NE(error.find("schema version 1"), std::string::npos) << error;
}

// CVO_MAP_CORRECTION as a tracker receives it: cut short, of another schema version, or counting
// more loops than it holds, it is refused by its kind before anything reads it.
TEST(Decode, AMapCorrectionCutShortOrOfAnotherVersionIsRefusedByKind) {
  const auto bytes = encode(test::sample_map_correction());
  auto failure = DecodeFailure::kContent;
  std::string error;
  EXPECT_FALSE(decode<cvo_lcm::map_correction_t>(bytes.data(), static_cast<int>(bytes.size()) - 1, &error, &failure));
  EXPECT_EQ(failure, DecodeFailure::kBody) << error;
  auto other = test::sample_map_correction();
  other.version = cvo_lcm::map_correction_t::SCHEMA_VERSION + 1;
  const auto newer = encode(other);
  EXPECT_FALSE(decode<cvo_lcm::map_correction_t>(newer.data(), static_cast<int>(newer.size()), &error, &failure));
  EXPECT_EQ(failure, DecodeFailure::kVersion);
  EXPECT_NE(error.find("cvo_lcm.map_correction_t: schema version " + std::to_string(other.version)), std::string::npos)
      << error;
  auto counted = bytes;  // num_loops follows the fixed header (wire_layout.cpp)
  const auto at = 8 + static_cast<std::size_t>(wire_layout("map_correction_t").counts.front().offset);
  ASSERT_EQ(counted[at + 3], 2) << "the sample's two loops";
  counted[at + 3] = 3;
  EXPECT_FALSE(decode<cvo_lcm::map_correction_t>(counted.data(), static_cast<int>(counted.size()), &error, &failure));
  EXPECT_EQ(failure, DecodeFailure::kBody);
  EXPECT_NE(error.find("truncated body"), std::string::npos) << error;
  EXPECT_TRUE(decode<cvo_lcm::map_correction_t>(bytes.data(), static_cast<int>(bytes.size()), &error)) << error;
}

void set_be32(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

TEST(Decode, HugeOrNegativeCountsAreRefusedBeforeAllocating) {
  auto bytes = encode(test::sample_keyframe());
  // fingerprint + its offset in the body (wire_layout.cpp; WireLayout tests check it against lcm-gen)
  const std::size_t num_points = 8 + static_cast<std::size_t>(wire_layout("keyframe_t").counts.front().offset);
  std::string error;
  set_be32(bytes, num_points, 0x7fffffff);
  EXPECT_FALSE(decode<cvo_lcm::keyframe_t>(bytes.data(), static_cast<int>(bytes.size()), &error));
  EXPECT_NE(error.find("truncated body"), std::string::npos) << error;
  set_be32(bytes, num_points, 0xfffffff0);
  EXPECT_FALSE(decode<cvo_lcm::keyframe_t>(bytes.data(), static_cast<int>(bytes.size()), &error));
  EXPECT_NE(error.find("negative count num_points"), std::string::npos) << error;
}

TEST(Decode, CorruptStringLengthIsRefused) {
  auto bytes = encode(test::sample_status());
  // The first string length follows the fixed fields: 8 + 4+8+8+4+1+3*8+5*8+4+8+17*8+5*8+1+8 = 294.
  const std::size_t process_length = 294;
  ASSERT_EQ(bytes[process_length + 3], std::string("cvo-trackerd").size() + 1);
  std::string error;
  for (std::uint32_t bad : {0u, 0xffffffffu, 0x80000000u, 1000000u}) {
    set_be32(bytes, process_length, bad);
    EXPECT_FALSE(decode<cvo_lcm::status_t>(bytes.data(), static_cast<int>(bytes.size()), &error)) << bad;
  }
}

// A NUL inside a string: lcm-gen's decoder would keep it, its encoder (strlen) drop the rest, so
// the message would not survive a round trip (found by fuzzing, fuzz/regressions/status).
TEST(Decode, AStringWithAnInnerNulIsRefused) {
  auto bytes = encode(test::sample_status());
  const std::size_t process_text = 294 + 4;  // "cvo-trackerd" after its length (see above)
  ASSERT_EQ(bytes[process_text], 'c');
  bytes[process_text + 3] = 0;  // "cvo\0trackerd"
  std::string error;
  EXPECT_FALSE(decode<cvo_lcm::status_t>(bytes.data(), static_cast<int>(bytes.size()), &error));
  EXPECT_NE(error.find("not one NUL-terminated text"), std::string::npos) << error;
}

// Each refusal says which check failed, so receivers count them by kind (CVO_STATUS bad_messages).
TEST(Decode, FailureKindNamesTheCheck) {
  const auto good = encode(test::sample_rgbd());
  const auto kind_of = [](const std::vector<std::uint8_t>& bytes) {
    auto failure = static_cast<DecodeFailure>(-1);  // none of the kinds: each must be set
    const auto decoded = decode<cvo_lcm::rgbd_frame_t>(bytes.data(), static_cast<int>(bytes.size()), nullptr, &failure);
    EXPECT_FALSE(decoded);
    return failure;
  };
  EXPECT_EQ(kind_of({1, 2, 3}), DecodeFailure::kTooShort);
  EXPECT_EQ(kind_of(encode(test::sample_pose_message())), DecodeFailure::kFingerprint);
  EXPECT_EQ(kind_of({good.begin(), good.end() - 1}), DecodeFailure::kBody);
  auto oversized = good;
  oversized.push_back(0);
  EXPECT_EQ(kind_of(oversized), DecodeFailure::kBody);
  auto other_version = test::sample_rgbd();
  other_version.version = 7;
  EXPECT_EQ(kind_of(encode(other_version)), DecodeFailure::kVersion);
  // The values are CVO_STATUS's indices.
  EXPECT_EQ(static_cast<int>(DecodeFailure::kTooShort), cvo_lcm::status_t::BAD_TOO_SHORT);
  EXPECT_EQ(static_cast<int>(DecodeFailure::kFingerprint), cvo_lcm::status_t::BAD_FINGERPRINT);
  EXPECT_EQ(static_cast<int>(DecodeFailure::kBody), cvo_lcm::status_t::BAD_BODY);
  EXPECT_EQ(static_cast<int>(DecodeFailure::kVersion), cvo_lcm::status_t::BAD_VERSION);

  DecodeFailure untouched = DecodeFailure::kFingerprint;
  EXPECT_TRUE(decode<cvo_lcm::rgbd_frame_t>(good.data(), static_cast<int>(good.size()), nullptr, &untouched));
  EXPECT_EQ(untouched, DecodeFailure::kFingerprint) << "left as it was on success";
}

template <class T>
void expect_garbage_fails(std::mt19937& rng, bool keep_fingerprint) {
  std::uniform_int_distribution<int> byte(0, 255), length(0, 400);
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(length(rng)));
    for (auto& b : bytes) b = static_cast<std::uint8_t>(byte(rng));
    if (keep_fingerprint && bytes.size() >= 8) {
      const auto hash = static_cast<std::uint64_t>(T::getHash());
      for (int i = 0; i < 8; ++i) bytes[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(hash >> (56 - 8 * i));
    }
    std::string error;
    const auto decoded = decode<T>(bytes.data(), static_cast<int>(bytes.size()), &error);
    // Random bytes after a right fingerprint can, rarely, be a valid message; otherwise say why.
    if (!decoded) {
      EXPECT_FALSE(error.empty());
    }
  }
}

TEST(Decode, RandomGarbageNeverCrashes) {
  std::mt19937 rng(12345);
  for (bool keep : {false, true}) {
    expect_garbage_fails<cvo_lcm::rgbd_frame_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::pose_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::keyframe_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::local_graph_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::map_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::map_correction_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::status_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::keyframe_request_t>(rng, keep);
    expect_garbage_fails<cvo_lcm::grid_t>(rng, keep);
  }
}

TEST(Decode, RandomGarbageWithoutTheFingerprintIsAlwaysRefused) {
  std::mt19937 rng(777);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int trial = 0; trial < 1000; ++trial) {
    std::vector<std::uint8_t> bytes(64);
    for (auto& b : bytes) b = static_cast<std::uint8_t>(byte(rng));
    std::string error;
    EXPECT_FALSE(decode<cvo_lcm::pose_t>(bytes.data(), 64, &error));
    EXPECT_NE(error.find("wrong fingerprint"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace cvo::lcm
