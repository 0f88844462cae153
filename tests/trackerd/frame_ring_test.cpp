// FrameRing: drop-oldest under overload, waiting in blocking mode, draining on close, and no
// allocation once constructed.
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "daemon/trackerd/frame_ring.hpp"
#include "program/allocation_counter.hpp"

namespace cvo::daemon::trackerd {
namespace {

using program::thread_allocations;

using namespace std::chrono_literals;

void put(FrameRing& ring, std::uint64_t index) {
  RingSlot* slot = ring.begin_write();
  ASSERT_NE(slot, nullptr);
  slot->frame.index = index;
  ring.commit_write();
}

std::uint64_t take(FrameRing& ring) {
  RingSlot* slot = ring.begin_read(100ms);
  EXPECT_NE(slot, nullptr);
  const auto index = slot ? slot->frame.index : 9999;
  ring.end_read();
  return index;
}

TEST(FrameRing, DropsTheOldestWhenFullAndCountsIt) {
  FrameRing ring(3, FrameRing::Overflow::kDropOldest);
  for (std::uint64_t i = 0; i < 7; ++i) put(ring, i);
  EXPECT_EQ(ring.dropped(), 4);
  EXPECT_EQ(ring.waiting(), 3u);
  EXPECT_EQ(take(ring), 4u);  // the newest three survive, in order
  EXPECT_EQ(take(ring), 5u);
  EXPECT_EQ(take(ring), 6u);
  EXPECT_EQ(ring.begin_read(10ms), nullptr);
}

TEST(FrameRing, BlockingModeWaitsForTheConsumerAndLosesNothing) {
  FrameRing ring(1, FrameRing::Overflow::kBlock);
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < 20; ++i) put(ring, i);
    ring.close();
  });
  std::vector<std::uint64_t> seen;
  while (RingSlot* slot = ring.begin_read(1000ms)) {
    seen.push_back(slot->frame.index);
    std::this_thread::sleep_for(1ms);  // a slow consumer
    ring.end_read();
  }
  producer.join();
  ASSERT_EQ(seen.size(), 20u);
  for (std::uint64_t i = 0; i < 20; ++i) EXPECT_EQ(seen[i], i);
  EXPECT_EQ(ring.dropped(), 0);
  EXPECT_TRUE(ring.drained());
}

TEST(FrameRing, CloseReleasesABlockedProducerAndDrainsTheConsumer) {
  FrameRing ring(1, FrameRing::Overflow::kBlock);
  put(ring, 1);
  std::thread producer([&] { EXPECT_EQ(ring.begin_write(), nullptr); });  // full: blocks until close
  std::this_thread::sleep_for(20ms);
  ring.close();
  producer.join();
  EXPECT_FALSE(ring.drained());
  EXPECT_EQ(take(ring), 1u);  // what was committed is still delivered
  EXPECT_EQ(ring.begin_read(10ms), nullptr);
  EXPECT_TRUE(ring.drained());
}

// A keyframe made at frame n is frame n-1, whose images the tracker shares: however fast frames
// come, the slot of the frame tracked last is not written again until the next one was tracked
// (end_read), nor when a frame is skipped; release_previous() gives it back.
TEST(FrameRing, TheFrameTrackedLastStaysUntilTheNextOneIsTracked) {
  FrameRing ring(1, FrameRing::Overflow::kDropOldest);
  put(ring, 0);
  RingSlot* previous = ring.begin_read(100ms);
  ASSERT_NE(previous, nullptr);
  ring.end_read();
  for (std::uint64_t i = 1; i < 10; ++i) put(ring, i);  // overload: every free slot is reused
  EXPECT_EQ(previous->frame.index, 0u) << "the previous frame's slot was written while kept";

  RingSlot* skipped = ring.begin_read(100ms);
  ASSERT_NE(skipped, nullptr);
  ring.skip_read();
  for (std::uint64_t i = 10; i < 20; ++i) put(ring, i);
  EXPECT_EQ(previous->frame.index, 0u) << "skipping a frame gave the previous one back";

  RingSlot* current = ring.begin_read(100ms);
  ASSERT_NE(current, nullptr);
  const auto tracked = current->frame.index;
  ring.end_read();  // now `current` is the previous frame, and frame 0's slot is free
  for (std::uint64_t i = 20; i < 30; ++i) put(ring, i);
  EXPECT_EQ(current->frame.index, tracked);

  ASSERT_NE(ring.begin_read(100ms), nullptr);  // the frame waiting: skipped
  ring.skip_read();
  ring.release_previous();  // the slot freed last is the next one written
  put(ring, 99);
  EXPECT_EQ(current->frame.index, 99u) << "release_previous() gave the slot back";
}

TEST(FrameRing, WritingAndReadingDoNotAllocate) {
  FrameRing ring(2, FrameRing::Overflow::kDropOldest);
  const auto before = thread_allocations();
  for (std::uint64_t i = 0; i < 100; ++i) {
    put(ring, i);
    if (i % 3 == 0) take(ring);
  }
  EXPECT_EQ(thread_allocations() - before, 0);
}

}  // namespace
}  // namespace cvo::daemon::trackerd
