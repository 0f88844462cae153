// Outbox: what the tracking thread could not hand to the publisher (no free keyframe or local-graph
// slot, or no room for the event) is counted lost, never silent, and its slots are free again.
#include <chrono>

#include <gtest/gtest.h>

#include "daemon/trackerd/outbox.hpp"

namespace cvo::daemon::trackerd {
namespace {

using namespace std::chrono_literals;

TEST(Outbox, AKeyframeOrGraphWithoutASlotIsCountedLost) {
  Outbox outbox(/*capacity=*/4, /*pool_size=*/1, 8, 6, 16, 4);
  const int keyframe = outbox.acquire_keyframe_slot(false);
  EXPECT_EQ(keyframe, 0);
  EXPECT_EQ(outbox.acquire_keyframe_slot(false), -1) << "the pool of one is taken";
  const int graph = outbox.acquire_graph_slot(false);
  EXPECT_EQ(graph, 0);
  EXPECT_EQ(outbox.acquire_graph_slot(false), -1);
  EXPECT_EQ(outbox.lost(), 2);

  Event event;
  event.keyframe_slot = keyframe;
  event.graph_slot = graph;
  ASSERT_TRUE(outbox.push(event, false));
  Event popped;
  ASSERT_TRUE(outbox.pop(popped, 10ms));
  outbox.release(popped);
  EXPECT_EQ(outbox.acquire_keyframe_slot(false), 0) << "released by the publisher";
  EXPECT_EQ(outbox.lost(), 2);
  EXPECT_EQ(outbox.dropped(), 0);
}

TEST(Outbox, AnEventDroppedForWantOfRoomLosesWhatItCarried) {
  Outbox outbox(/*capacity=*/1, /*pool_size=*/2, 8, 6, 16, 4);
  ASSERT_TRUE(outbox.push(Event{}, false));  // a pose only: the outbox is full now
  Event event;
  event.keyframe_slot = outbox.acquire_keyframe_slot(false);
  event.graph_slot = outbox.acquire_graph_slot(false);
  ASSERT_GE(event.keyframe_slot, 0);
  ASSERT_GE(event.graph_slot, 0);
  EXPECT_FALSE(outbox.push(event, false));
  EXPECT_EQ(outbox.dropped(), 1);
  EXPECT_EQ(outbox.lost(), 2) << "its keyframe and its local graph";
  EXPECT_FALSE(outbox.push(Event{}, false));
  EXPECT_EQ(outbox.lost(), 2) << "a dropped pose carries neither";
  EXPECT_GE(outbox.acquire_keyframe_slot(false), 0) << "the dropped event's slots are free again";
  EXPECT_GE(outbox.acquire_keyframe_slot(false), 0);
}

}  // namespace
}  // namespace cvo::daemon::trackerd
