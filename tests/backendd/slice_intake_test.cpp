// Slices before they are put together (daemon/backendd/slice_intake.hpp), on a clock of their own:
// a forger's first slices do not keep a live session's keyframes out; a flood of slices of
// sessions whose tracker is not heard is counted refused, asks for nothing, loses nothing, and
// stays within its room; a killed session's hand-over still comes in.
#include <chrono>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/backendd/keyframe_gaps.hpp"
#include "daemon/backendd/slice_intake.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/wire_layout.hpp"

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;
using Chunk = cvo_lcm::keyframe_chunk_t;
using Outcome = lcm::ChunkAssembly::Added::Outcome;
using Bytes = std::vector<std::uint8_t>;
using Clock = SliceIntake::Clock;
constexpr std::size_t kData = Chunk::MAX_DATA;
constexpr std::int64_t kSession = 0x5e5510'0000'0001;
const Clock::time_point t0{};

Bytes message_of(std::size_t size, std::uint8_t seed) {
  Bytes bytes(size);
  std::iota(bytes.begin(), bytes.end(), seed);
  std::fill(bytes.end() - lcm::kAuthTrailerBytes, bytes.end(), 0);
  return bytes;
}

std::vector<Chunk> slices_of(const Bytes& message, const lcm::SlicedName& name) {
  std::vector<Chunk> out;
  const auto crc = lcm::content_crc(message.data(), message.size());
  for (std::int32_t k = 0; k < lcm::slice_count(message.size()); ++k) out.push_back(lcm::slice(message, name, crc, k));
  return out;
}

// The keyframe the slices put together, if they did.
std::optional<Bytes> put_together(SliceIntake& intake, KeyframeGaps& gaps, const std::vector<Chunk>& slices,
                                  Clock::time_point now) {
  for (const auto& c : slices)
    if (auto added = intake.add(c, gaps, now); added.outcome == Outcome::kComplete) return std::move(added.message);
  return std::nullopt;
}

Chunk random_slice(std::mt19937_64& random) {
  Chunk c{};
  c.session = static_cast<std::int64_t>(random());
  c.id = static_cast<std::int64_t>(random() % 1'000'000);
  c.message = static_cast<std::int8_t>(random() % 2);
  c.message_size = static_cast<std::int32_t>(kData * (1 + random() % 1000));
  c.message_crc = static_cast<std::int32_t>(random());
  c.index = static_cast<std::int32_t>(random() % static_cast<std::uint64_t>(c.message_size / kData));
  c.data.assign(kData, 0x42);
  c.data_size = static_cast<std::int32_t>(kData);
  return c;
}

TEST(SliceIntake, ForgedFirstSlicesOfALiveSessionsNextKeyframesDoNotKeepTheGenuineOnesOut) {
  SliceIntake intake;
  KeyframeGaps gaps;
  intake.heard(kSession, t0, 0);
  for (std::int64_t id = 1; id <= 20; ++id) {  // the forger is first, on every name to come
    auto forged = slices_of(message_of(50 * kData, 99), {kSession, id, Chunk::KEYFRAME}).front();
    EXPECT_NE(intake.add(forged, gaps, t0).outcome, Outcome::kRefused);
  }
  for (std::int64_t id = 1; id <= 20; ++id) {
    const auto genuine = message_of(30 * kData + 7, static_cast<std::uint8_t>(id));
    EXPECT_EQ(put_together(intake, gaps, slices_of(genuine, {kSession, id, Chunk::KEYFRAME}), t0 + 10ms), genuine)
        << "keyframe " << id;
  }
}

TEST(SliceIntake, AFloodOfSlicesOfSessionsNotHeardIsCountedRefusedAsksForNothingAndStaysInItsRoom) {
  const SliceIntake::Limits limits;
  SliceIntake intake(limits);
  KeyframeGaps gaps;
  std::mt19937_64 random(48);
  constexpr std::int64_t kFlood = 30'000;  // ten seconds of the audit's 3 000 a second
  std::int64_t refused = 0;                // a message of one slice whose CRC is wrong: refused at once
  for (std::int64_t n = 0; n < kFlood; ++n) {
    const auto added = intake.add(random_slice(random), gaps, t0 + std::chrono::milliseconds(n / 3));
    refused += added.outcome == Outcome::kRefused ? 1 : 0;
    ASSERT_LE(intake.held(), limits.strangers.max_messages);
  }
  EXPECT_LE(intake.bytes(), limits.strangers.max_messages * (kData + lcm::ChunkAssembly::kSliceOverhead));
  EXPECT_EQ(intake.strangers_dropped() + static_cast<std::int64_t>(intake.held()) + refused, kFlood);
  EXPECT_EQ(intake.strangers_dropped(), 0) << "each counted once";
  for (const auto later : {1s, 10s, 100s}) EXPECT_TRUE(gaps.due(t0 + later).requests.empty());
  EXPECT_EQ(gaps.requested(), 0);
  EXPECT_EQ(gaps.lost(), 0) << "a forged name is no keyframe lost";
}

TEST(SliceIntake, AFloodDoesNotKeepOutALiveSessionsKeyframeNorAKilledSessionsHandOver) {
  SliceIntake intake;
  KeyframeGaps gaps;
  intake.heard(kSession, t0, 4);
  std::mt19937_64 random(7);
  const auto live = message_of(200 * kData, 1), handed_over = message_of(200 * kData, 2);
  const auto live_slices = slices_of(live, {kSession, 4, Chunk::KEYFRAME});
  const auto handed_slices = slices_of(handed_over, {kSession + 1, 9, Chunk::KEYFRAME});  // its tracker was killed
  std::optional<Bytes> live_done, handed_done;
  for (std::size_t k = 0; k < live_slices.size(); ++k) {
    // A tracker sends 8 slices a millisecond (trackerd/slice_pacer.hpp): four forged between two of
    // its own is a flood of 32 000 a second, ten times the audit's.
    for (int n = 0; n < 4; ++n) intake.add(random_slice(random), gaps, t0);
    if (auto a = intake.add(live_slices[k], gaps, t0); a.outcome == Outcome::kComplete) live_done = a.message;
    if (auto a = intake.add(handed_slices[k], gaps, t0); a.outcome == Outcome::kComplete) handed_done = a.message;
  }
  EXPECT_EQ(live_done, live);
  EXPECT_EQ(handed_done, handed_over);
}

TEST(SliceIntake, WhatALiveSessionsKeyframeLacksIsAskedForAndAStrangersIsNot) {
  SliceIntake intake;
  KeyframeGaps gaps;
  intake.heard(kSession, t0, 0);
  const auto message = message_of(10 * kData, 3);
  auto mine = slices_of(message, {kSession, 0, Chunk::KEYFRAME});
  auto theirs = slices_of(message, {kSession + 1, 0, Chunk::KEYFRAME});
  for (std::size_t k = 0; k + 3 < mine.size(); ++k) intake.add(mine[k], gaps, t0), intake.add(theirs[k], gaps, t0);
  const auto round = gaps.due(t0 + 2s);
  ASSERT_EQ(round.requests.size(), 1u);
  EXPECT_EQ(round.requests.front().session, kSession);
  EXPECT_EQ(intake.missing({kSession, 0, Chunk::KEYFRAME}, 4), (std::vector<lcm::SliceRange>{{7, 3}}));
}

TEST(SliceIntake, ForgedNamesPastTheNewestKeyframeALiveSessionsPosesNamedAreNeverAskedForNorCountedLost) {
  SliceIntake intake;
  KeyframeGaps gaps;
  intake.heard(kSession, t0, 11);
  for (std::int64_t id = 12; id <= 16; ++id)
    intake.add(slices_of(message_of(50 * kData, 9), {kSession, id, Chunk::KEYFRAME}).front(), gaps, t0);
  EXPECT_TRUE(gaps.due(t0 + 2s).requests.empty());
  gaps.give_up_all();
  EXPECT_EQ(gaps.lost(), 0);
}

TEST(SliceIntake, ASessionIsLiveWhileItsTrackerIsHeardWithinTheWindow) {
  SliceIntake intake({.alive_window = 5000ms, .max_sessions = 2});
  EXPECT_FALSE(intake.live(kSession, t0));
  intake.heard(kSession, t0, std::nullopt);
  EXPECT_TRUE(intake.live(kSession, t0 + 5s));
  EXPECT_FALSE(intake.live(kSession, t0 + 6s));
  intake.heard(kSession + 1, t0 + 1s, 0);
  intake.heard(kSession + 2, t0 + 2s, 0);  // two at most: the least recently heard goes
  EXPECT_FALSE(intake.live(kSession, t0 + 2s));
  EXPECT_TRUE(intake.live(kSession + 1, t0 + 2s));
}

}  // namespace
}  // namespace cvo::daemon::backendd
