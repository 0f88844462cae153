// FrameGaps and pair_action: the bookkeeping that keeps lost frames counted.
#include <gtest/gtest.h>

#include "drivers/frame_gaps.hpp"
#include "drivers/stream_pairing.hpp"

namespace cvo::drivers {
namespace {

TEST(FrameGaps, ConsecutiveFramesLoseNothing) {
  FrameGaps gaps;
  for (int i = 0; i < 10; ++i) gaps.arrived(i);
  EXPECT_EQ(gaps.lost(), 0u);
}

TEST(FrameGaps, AJumpLosesTheFramesBetween) {
  FrameGaps gaps;
  gaps.arrived(3);  // a stream may start anywhere
  gaps.arrived(4);
  gaps.arrived(7);
  EXPECT_EQ(gaps.lost(), 2u);
  gaps.arrived(100);
  EXPECT_EQ(gaps.lost(), 2u + 92u);
}

TEST(FrameGaps, UnreadableMessagesAreNotCountedTwice) {
  FrameGaps gaps;
  gaps.arrived(0);
  gaps.unreadable();  // frame 1 arrived but did not decode: already counted as bad input
  gaps.arrived(2);
  EXPECT_EQ(gaps.lost(), 0u);
  gaps.unreadable();
  gaps.arrived(6);  // 3, 4, 5 missing, one of them arrived unreadable
  EXPECT_EQ(gaps.lost(), 2u);
}

TEST(FrameGaps, ARestartedSenderStartsANewStream) {
  FrameGaps gaps;
  gaps.arrived(50);
  gaps.arrived(0);
  gaps.arrived(1);
  gaps.arrived(1);  // a repeat
  EXPECT_EQ(gaps.lost(), 0u);
}

TEST(PairAction, CloseFramesPairAndTheOlderOfTwoDistantOnesIsDropped) {
  EXPECT_EQ(pair_action(10.000, 10.010, 0.0167), PairAction::kPair);
  EXPECT_EQ(pair_action(10.010, 10.000, 0.0167), PairAction::kPair);
  EXPECT_EQ(pair_action(10.000, 10.033, 0.0167), PairAction::kDropColour);
  EXPECT_EQ(pair_action(10.033, 10.000, 0.0167), PairAction::kDropDepth);
}

}  // namespace
}  // namespace cvo::drivers
