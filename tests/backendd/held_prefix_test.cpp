// What cvo-backendd acknowledges of each tracker session (daemon/backendd/held_prefix.hpp): the prefix
// of keyframe ids held each with its local graph, advanced only when both of the next id are held, in
// whatever order they come; what is held below it is ignored, a merged keyframe counts as both, and
// sessions are kept apart.
#include <cstdint>
#include <map>

#include <gtest/gtest.h>

#include "daemon/backendd/held_prefix.hpp"

namespace cvo::daemon::backendd {
namespace {

constexpr std::int64_t kSession = 0x5e5510'0000'0001;
constexpr std::int64_t kOther = 0x5e5510'0000'0002;
constexpr bool kKeyframe = false, kGraph = true;

TEST(HeldPrefix, AnUnknownSessionHasNothingAcknowledged) {
  const HeldPrefix held;
  EXPECT_EQ(held.acknowledged(kSession), 0);
}

TEST(HeldPrefix, TheSessionsWhosePrefixGrewAreTakenOnce) {
  HeldPrefix held;
  held.held(kSession, 0, kKeyframe);
  EXPECT_TRUE(held.take_grown().empty()) << "a keyframe without its graph does not grow the prefix";
  held.held(kSession, 0, kGraph);
  held.merged(kOther, 0);
  held.held(kSession, 1, kKeyframe);
  held.held(kSession, 1, kGraph);
  const std::map<std::int64_t, std::int64_t> grown{{kSession, 2}, {kOther, 1}};
  EXPECT_EQ(held.take_grown(), grown);
  EXPECT_TRUE(held.take_grown().empty()) << "taken already";
}

TEST(HeldPrefix, TheKeyframeAloneOrItsGraphAloneIsNotHeld) {
  HeldPrefix held;
  held.held(kSession, 0, kKeyframe);
  EXPECT_EQ(held.acknowledged(kSession), 0);
  held.held(kSession, 1, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 0);
  held.held(kSession, 0, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 1) << "keyframe 1 still lacks its keyframe";
  held.held(kSession, 1, kKeyframe);
  EXPECT_EQ(held.acknowledged(kSession), 2);
}

TEST(HeldPrefix, ThePrefixAdvancesInAnyOrderOfArrival) {
  HeldPrefix held;
  // Keyframes 1-4 complete, in a scrambled order, with a gap at 0.
  held.held(kSession, 4, kGraph);
  held.held(kSession, 2, kKeyframe);
  held.held(kSession, 1, kGraph);
  held.held(kSession, 3, kKeyframe);
  held.held(kSession, 4, kKeyframe);
  held.held(kSession, 1, kKeyframe);
  held.held(kSession, 3, kGraph);
  held.held(kSession, 2, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 0) << "keyframe 0 is missing";
  held.held(kSession, 0, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 0);
  held.held(kSession, 0, kKeyframe);  // fills the gap: everything held above follows
  EXPECT_EQ(held.acknowledged(kSession), 5);
  held.held(kSession, 6, kKeyframe);
  held.held(kSession, 6, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 5) << "keyframe 5 is missing";
}

TEST(HeldPrefix, WhatIsHeldBelowThePrefixIsIgnored) {
  HeldPrefix held;
  for (std::int64_t k = 0; k < 3; ++k) held.merged(kSession, k);
  ASSERT_EQ(held.acknowledged(kSession), 3);
  held.held(kSession, 1, kKeyframe);  // stored again (read back at start, or sent again)
  held.held(kSession, 2, kGraph);
  held.held(kSession, -1, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 3);
  held.held(kSession, 3, kKeyframe);  // the next ones still need both
  EXPECT_EQ(held.acknowledged(kSession), 3);
  held.held(kSession, 3, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 4);
}

TEST(HeldPrefix, HeldTwiceCountsOnce) {
  HeldPrefix held;
  held.held(kSession, 0, kKeyframe);
  held.held(kSession, 0, kKeyframe);
  EXPECT_EQ(held.acknowledged(kSession), 0) << "the keyframe twice is not its graph";
  held.held(kSession, 0, kGraph);
  held.held(kSession, 0, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 1);
}

TEST(HeldPrefix, AMergedKeyframeCountsAsKeyframeAndGraph) {
  HeldPrefix held;
  held.held(kSession, 0, kKeyframe);
  held.held(kSession, 0, kGraph);
  held.merged(kSession, 1);  // merged into keyframe 0: its merge record stands for both
  EXPECT_EQ(held.acknowledged(kSession), 2);
  held.held(kSession, 3, kKeyframe);
  held.held(kSession, 3, kGraph);
  held.merged(kSession, 2);
  EXPECT_EQ(held.acknowledged(kSession), 4);
  held.held(kSession, 4, kKeyframe);
  held.merged(kSession, 4);  // one part stored, then merged: both
  EXPECT_EQ(held.acknowledged(kSession), 5);
}

TEST(HeldPrefix, SessionsAreAcknowledgedEachOnItsOwn) {
  HeldPrefix held;
  held.held(kSession, 0, kKeyframe);
  held.held(kOther, 0, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 0) << "the other session's graph 0 is not ours";
  EXPECT_EQ(held.acknowledged(kOther), 0);
  held.merged(kOther, 1);
  held.held(kOther, 0, kKeyframe);
  EXPECT_EQ(held.acknowledged(kOther), 2);
  EXPECT_EQ(held.acknowledged(kSession), 0);
  held.held(kSession, 0, kGraph);
  EXPECT_EQ(held.acknowledged(kSession), 1);
  EXPECT_EQ(held.acknowledged(0x7777), 0) << "never heard of";
}

}  // namespace
}  // namespace cvo::daemon::backendd
