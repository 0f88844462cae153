// cvo-trackerd's pacing of keyframe slices (daemon/trackerd/slice_pacer.hpp): at most kBurst slices
// per kTick, in the order they were added, each the slice of its message it names.
#include <chrono>
#include <cstdint>
#include <memory>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/trackerd/slice_pacer.hpp"

namespace cvo::daemon::trackerd {
namespace {

using namespace std::chrono_literals;
using Chunk = cvo_lcm::keyframe_chunk_t;
constexpr std::size_t kData = Chunk::MAX_DATA;

std::shared_ptr<const std::vector<std::uint8_t>> message_of(std::size_t slices) {
  auto bytes = std::make_shared<std::vector<std::uint8_t>>(slices * kData);
  std::iota(bytes->begin(), bytes->end(), 0);
  return bytes;
}

TEST(SlicePacer, SendsAtMostABurstATickInTheOrderAdded) {
  SlicePacer pacer;
  const SlicePacer::Clock::time_point t0{1h};
  pacer.add({1, 0, Chunk::KEYFRAME}, message_of(10), 7, {0, 10});
  pacer.add({1, 0, Chunk::LOCAL_GRAPH}, message_of(2), 8, {1, 5});  // one slice: it has two
  EXPECT_EQ(pacer.waiting(), 11u);
  std::vector<Chunk> sent;
  const auto send = [&](const Chunk& c) { sent.push_back(c); };
  EXPECT_EQ(pacer.send_due(t0, send), SlicePacer::kBurst);
  EXPECT_EQ(pacer.send_due(t0 + SlicePacer::kTick / 2, send), 0u) << "within a tick of the last burst";
  EXPECT_EQ(pacer.send_due(t0 + SlicePacer::kTick, send), 11 - SlicePacer::kBurst);
  EXPECT_TRUE(pacer.idle());
  ASSERT_EQ(sent.size(), 11u);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(sent[static_cast<std::size_t>(k)].message, +Chunk::KEYFRAME);
    EXPECT_EQ(sent[static_cast<std::size_t>(k)].index, k);
    EXPECT_EQ(sent[static_cast<std::size_t>(k)].message_crc, 7);
  }
  EXPECT_EQ(sent[10].message, +Chunk::LOCAL_GRAPH);
  EXPECT_EQ(sent[10].index, 1);
  EXPECT_EQ(sent[10].data[0], static_cast<std::uint8_t>(kData % 256)) << "slice 1's bytes";
}

TEST(SlicePacer, ARangePastTheMessageAddsNothing) {
  SlicePacer pacer;
  pacer.add({1, 0, Chunk::KEYFRAME}, message_of(2), 7, {5, 3});
  EXPECT_TRUE(pacer.idle());
}

}  // namespace
}  // namespace cvo::daemon::trackerd
