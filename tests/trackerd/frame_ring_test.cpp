// FrameRing: drop-oldest under overload, waiting in blocking mode, draining on close, and no
// allocation once constructed.
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "program/allocation_counter.hpp"
#include "daemon/trackerd/frame_ring.hpp"

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
