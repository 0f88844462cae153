// Keyframes in slices of one datagram (libcvo/lcm/chunks.hpp): a message sliced and put back
// together in any order is the same message; a slice twice is a repeat; what is missing is reported
// as ranges, the closest holes merged when there are too many; slices that do not fit their message,
// or of another message of the same name, are refused; memory stays within its bounds.
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/wire_layout.hpp"
#include "tests/lcm/sample_messages.hpp"

namespace cvo::lcm {
namespace {

using Chunk = cvo_lcm::keyframe_chunk_t;
using Outcome = ChunkAssembly::Added::Outcome;
using Bytes = std::vector<std::uint8_t>;
constexpr std::size_t kData = Chunk::MAX_DATA;
const SlicedName kName{0x5e5510'0000'0001, 7, Chunk::KEYFRAME};

Bytes message_of(std::size_t size, std::uint8_t seed = 1) {
  Bytes bytes(size);
  std::iota(bytes.begin(), bytes.end(), seed);
  std::fill(bytes.end() - kAuthTrailerBytes, bytes.end(), 0);  // unsigned: the slices are signed
  return bytes;
}

std::vector<Chunk> slices_of(const Bytes& message, const SlicedName& name = kName) {
  std::vector<Chunk> out;
  const auto crc = content_crc(message.data(), message.size());
  for (std::int32_t k = 0; k < slice_count(message.size()); ++k) out.push_back(slice(message, name, crc, k));
  return out;
}

TEST(Chunks, EverySliceFitsOnePacketOfAnEthernetLinkOrACommonTunnel) {
  const auto message = message_of(3 * kData);
  const auto chunk = slices_of(message).front();
  // LCM's small-message header (8 bytes), the channel and its NUL, the message; then UDP and IPv4.
  const std::size_t datagram = 8 + std::string("CVO_KEYFRAME_CHUNK").size() + 1 + encode(chunk).size();
  EXPECT_LE(datagram + 8 + 20, 1420u) << "WireGuard's MTU, the smallest of the common tunnels'";
}

TEST(Chunks, AMessageSlicedAndPutTogetherInAnyOrderIsTheSameMessage) {
  const auto message = message_of(5 * kData + 123);
  auto slices = slices_of(message);
  ASSERT_EQ(slices.size(), 6u);
  EXPECT_EQ(slices.back().data_size, 123);
  std::shuffle(slices.begin(), slices.end(), std::mt19937(5));
  ChunkAssembly assembly;
  for (std::size_t k = 0; k + 1 < slices.size(); ++k) EXPECT_EQ(assembly.add(slices[k]).outcome, Outcome::kPartial);
  EXPECT_EQ(assembly.add(slices[2]).outcome, Outcome::kRepeat) << "a slice held already";
  const auto done = assembly.add(slices.back());
  ASSERT_EQ(done.outcome, Outcome::kComplete) << done.why;
  EXPECT_EQ(done.message, message);
  EXPECT_EQ(assembly.held(), 0u);
  EXPECT_EQ(assembly.bytes(), 0u);
}

TEST(Chunks, WhatIsMissingIsReportedAsRangesTheClosestHolesMergedWhenThereAreTooMany) {
  const auto message = message_of(20 * kData);
  const auto slices = slices_of(message);
  ChunkAssembly assembly;
  EXPECT_FALSE(assembly.missing(kName, 4)) << "nothing of it held";
  for (const int k : {0, 1, 4, 5, 6, 8, 15, 16, 17, 18, 19}) assembly.add(slices[static_cast<std::size_t>(k)]);
  // Missing: 2-3, 7, 9-14.
  EXPECT_EQ(*assembly.missing(kName, 4), (std::vector<SliceRange>{{2, 2}, {7, 1}, {9, 6}}));
  // Two ranges: 7 and 9-14 are closer (one slice between them) than 2-3 and 7 (three).
  EXPECT_EQ(*assembly.missing(kName, 2), (std::vector<SliceRange>{{2, 2}, {7, 8}}));
  EXPECT_EQ(*assembly.missing(kName, 1), (std::vector<SliceRange>{{2, 13}}));
  EXPECT_FALSE(assembly.missing({kName.session, kName.id, Chunk::LOCAL_GRAPH}, 4)) << "its graph: nothing held";
}

TEST(Chunks, SlicesThatDoNotFitTheirMessageAreRefusedAsBadContent) {
  const auto message = message_of(2 * kData + 10);
  const auto good = slices_of(message);
  const auto refused = [](const Chunk& c) {
    ChunkAssembly assembly;
    const auto added = assembly.add(c);
    EXPECT_EQ(added.refusal, core::BadKind::kContent) << added.why;
    return added.outcome == Outcome::kRefused && assembly.held() == 0;
  };
  auto c = good[0];
  c.index = 3;  // past its last slice
  EXPECT_TRUE(refused(c));
  c = good[0];
  c.index = -1;
  EXPECT_TRUE(refused(c));
  c = good[0];
  c.data.pop_back();  // shorter than its slice
  c.data_size = static_cast<std::int32_t>(c.data.size());
  EXPECT_TRUE(refused(c));
  c = good[2];
  c.message_size = 20;  // no room for the auth trailer
  EXPECT_TRUE(refused(c));
  c = good[0];
  c.message = 5;  // neither a keyframe nor a local graph
  EXPECT_TRUE(refused(c));
}

TEST(Chunks, SlicesOfAnotherMessageOfTheSameNameAreNeverPutTogether) {
  const auto message = message_of(3 * kData), other = message_of(3 * kData, 9);
  const auto mine = slices_of(message), theirs = slices_of(other);
  ChunkAssembly assembly;
  assembly.add(mine[0]);
  EXPECT_EQ(assembly.add(theirs[1]).outcome, Outcome::kPartial) << "held apart, by its CRC";
  assembly.add(mine[1]);
  EXPECT_EQ(assembly.add(mine[2]).message, message);
  assembly.add(theirs[0]);
  EXPECT_EQ(assembly.add(theirs[2]).message, other);
}

// Issue 48: one forged first slice for each of a live session's next keyframe names held them,
// and the genuine slices were refused as conflicts.
TEST(Chunks, AForgedFirstSliceDoesNotLockItsNameTheGenuineKeyframeCompletesAndDecodes) {
  auto keyframe = test::sample_keyframe();
  keyframe.colour.resize(5 * kData, 0x42);  // a keyframe of several slices
  keyframe.colour_size = static_cast<std::int32_t>(keyframe.colour.size());
  const auto genuine = encode(keyframe);
  const SlicedName name{keyframe.session, keyframe.id, Chunk::KEYFRAME};
  const auto slices = slices_of(genuine, name);
  ASSERT_GE(slices.size(), 2u);
  auto forged = slices.front();  // a forger who has not seen the keyframe yet guesses its size and CRC
  forged.message_size += 3 * static_cast<std::int32_t>(kData);
  forged.message_crc ^= 0x5a5a;
  forged.data.assign(kData, 0xee);
  ChunkAssembly assembly;
  ASSERT_EQ(assembly.add(forged).outcome, Outcome::kPartial);
  Bytes put_together;
  for (const auto& c : slices) {
    auto added = assembly.add(c);
    ASSERT_NE(added.outcome, Outcome::kRefused) << added.why;
    if (added.outcome == Outcome::kComplete) put_together = std::move(added.message);
  }
  ASSERT_EQ(put_together, genuine);
  EXPECT_TRUE(decode<cvo_lcm::keyframe_t>(put_together.data(), static_cast<int>(put_together.size()), nullptr));
  assembly.forget(name);
  EXPECT_EQ(assembly.held(), 0u) << "the forgery competes in vain once the keyframe is let in";
  EXPECT_EQ(assembly.bytes(), 0u);
}

TEST(Chunks, ManyCompetingMessagesOfOneNameStayBoundedAndTheOneWellUnderWayStays) {
  const auto message = message_of(8 * kData);
  const auto mine = slices_of(message);
  ChunkAssembly assembly({.max_messages = 64, .max_bytes = std::size_t{1} << 20, .max_per_name = 4});
  for (int k = 0; k < 4; ++k) assembly.add(mine[static_cast<std::size_t>(k)]);
  for (std::uint8_t seed = 10; seed < 210; ++seed) {  // 200 forgeries of the same name
    const auto forged = slices_of(message_of(8 * kData, seed));
    assembly.add(forged[seed % 8]);
    EXPECT_LE(assembly.held(), 4u);
  }
  EXPECT_GE(assembly.dropped(), 196);
  Bytes put_together;
  for (std::size_t k = 4; k < mine.size(); ++k)
    if (auto added = assembly.add(mine[k]); added.outcome == Outcome::kComplete) put_together = added.message;
  EXPECT_EQ(put_together, message) << "forgeries of one slice each make way for the message holding four";
}

TEST(Chunks, AFloodOfRandomSlicesStaysWithinTheRoomAndItsSlicesAreCountedWhenDropped) {
  const ChunkAssembly::Limits limits{.max_messages = 16};
  const std::size_t room = limits.max_messages * (kData + ChunkAssembly::kSliceOverhead);
  ChunkAssembly assembly(limits);
  std::mt19937_64 random(48);
  constexpr int kFlood = 20000;
  for (int n = 0; n < kFlood; ++n) {
    Chunk c{};
    c.session = static_cast<std::int64_t>(random());
    c.id = static_cast<std::int64_t>(random() % 1000);
    c.message = Chunk::KEYFRAME;
    c.message_size = 100 << 20;  // claims 100 MiB: never allocated ahead
    c.message_crc = static_cast<std::int32_t>(random());
    c.index = static_cast<std::int32_t>(random() % 1000);
    c.data.assign(kData, 0x42);
    c.data_size = static_cast<std::int32_t>(kData);
    assembly.add(c);
    ASSERT_LE(assembly.bytes(), room) << "one slice of each message, whatever size it claims";
    ASSERT_LE(assembly.held(), limits.max_messages);
  }
  EXPECT_EQ(assembly.dropped_slices() + static_cast<std::int64_t>(assembly.held()), kFlood);
}

TEST(Chunks, SlicesWhoseBytesDoNotGiveTheirCrcAreRefusedWhole) {
  const auto message = message_of(2 * kData);
  auto slices = slices_of(message);
  slices[1].data[5] ^= 1;  // corrupted, or forged, after the CRC was taken
  ChunkAssembly assembly;
  assembly.add(slices[0]);
  const auto added = assembly.add(slices[1]);
  EXPECT_EQ(added.outcome, Outcome::kRefused);
  EXPECT_EQ(added.refusal, core::BadKind::kContent);
  EXPECT_EQ(assembly.held(), 0u) << "dropped: asked for again whole";
}

TEST(Chunks, TheMessageHoldingFewestSlicesLeastRecentlyAddedToIsDroppedForRoom) {
  ChunkAssembly assembly({.max_messages = 2, .max_bytes = 10 * kData});
  const auto first = slices_of(message_of(4 * kData), {1, 0, Chunk::KEYFRAME});
  const auto second = slices_of(message_of(4 * kData), {1, 1, Chunk::KEYFRAME});
  const auto third = slices_of(message_of(4 * kData), {1, 2, Chunk::KEYFRAME});
  assembly.add(first[0]);
  assembly.add(second[0]);
  assembly.add(first[1]);  // first is now the more recent
  assembly.add(third[0]);  // two at most: second (one slice) goes
  EXPECT_EQ(assembly.held(), 2u);
  EXPECT_EQ(assembly.dropped(), 1);
  EXPECT_TRUE(assembly.missing({1, 0, Chunk::KEYFRAME}, 1));
  EXPECT_FALSE(assembly.missing({1, 1, Chunk::KEYFRAME}, 1));
  const auto huge = slices_of(message_of(11 * kData), {1, 3, Chunk::KEYFRAME});
  EXPECT_EQ(assembly.add(huge[0]).outcome, Outcome::kRefused) << "larger than all the room";
  EXPECT_LE(assembly.bytes(), 10 * kData);
}

TEST(Chunks, ARangeIsClampedToTheSlicesItsMessageHas) {
  EXPECT_EQ(clamp({2, 100}, 4 * kData), (SliceRange{2, 2}));
  EXPECT_EQ(clamp({5, 1}, 4 * kData), (SliceRange{4, 0}));
  EXPECT_EQ(clamp({-3, 5}, 4 * kData), (SliceRange{0, 2}));
  EXPECT_EQ(clamp({0, std::numeric_limits<std::int32_t>::max()}, kData + 1), (SliceRange{0, 2}));
}

TEST(Chunks, TheContentCrcLeavesOutTheAuthTrailer) {
  auto message = message_of(kData);
  const auto crc = content_crc(message.data(), message.size());
  message.back() = 0x55;  // signed afresh
  EXPECT_EQ(content_crc(message.data(), message.size()), crc);
  message.front() ^= 1;
  EXPECT_NE(content_crc(message.data(), message.size()), crc);
}

}  // namespace
}  // namespace cvo::lcm
