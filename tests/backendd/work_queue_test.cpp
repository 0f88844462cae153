// The back end's work queue: bounded for live input, waiting for a log, unbounded for a replay.
#include "daemon/backendd/work_queue.hpp"

#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;

TEST(WorkQueue, HasRoomUpToItsCapacityAndPopsInOrder) {
  WorkQueue<int> queue(2);
  EXPECT_TRUE(queue.has_room());
  queue.push(1);
  queue.push(2);
  EXPECT_FALSE(queue.has_room()) << "a third live record would be refused";
  EXPECT_EQ(queue.pop(0ms), 1);
  EXPECT_TRUE(queue.has_room());
  EXPECT_EQ(queue.pop(0ms), 2);
  EXPECT_FALSE(queue.pop(10ms)) << "empty: nothing comes";
}

TEST(WorkQueue, AWaitingProducerGetsRoomWhenTheConsumerTakesOne) {
  WorkQueue<int> queue(1);
  queue.push(1);
  std::atomic<bool> got_room{false};
  std::thread producer([&] {
    got_room = queue.wait_for_room([] { return false; }, 5ms);
    queue.push(2);
  });
  EXPECT_EQ(queue.pop(1s), 1);
  EXPECT_EQ(queue.pop(10s), 2);  // pushed only once there was room
  producer.join();
  EXPECT_TRUE(got_room);
}

TEST(WorkQueue, AWaitingProducerGivesUpWhenTold) {
  WorkQueue<int> queue(1);
  queue.push(1);
  EXPECT_FALSE(queue.wait_for_room([] { return true; }));
  EXPECT_EQ(queue.size(), 1u);
}

TEST(WorkQueue, AReplayFromTheStoreIsNotBoundedButLiveInputThenWaits) {
  WorkQueue<int> queue(2);
  for (int i = 0; i < 5; ++i) queue.push(i);  // records already on disk
  EXPECT_EQ(queue.size(), 5u);
  EXPECT_FALSE(queue.has_room());
  for (int i = 0; i < 4; ++i) EXPECT_EQ(queue.pop(0ms), i);
  EXPECT_TRUE(queue.has_room());
}

}  // namespace
}  // namespace cvo::daemon::backendd
