// cvo-trackerd's keyframe history (daemon/trackerd/keyframe_history.hpp): the last N keyframes and
// their local graphs kept as sent, the answer to a request (keyframe then graph, byte for byte), what
// is counted lost (an id beyond the history, once however often asked) and what is not (another
// tracker's session, an id never made), and no allocation once constructed.
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/trackerd/keyframe_history.hpp"
#include "program/allocation_counter.hpp"

namespace cvo::daemon::trackerd {
namespace {

using program::thread_allocations;

using Bytes = std::vector<std::uint8_t>;
using Ids = std::vector<std::int64_t>;
constexpr std::int64_t kSession = 0x5e5510'0000'0001;
constexpr std::size_t kSlots = 4;

// Distinct content for each message (its id and kind in the bytes).
Bytes message(std::int64_t id, std::uint8_t kind, std::size_t size = 100) {
  Bytes bytes(size, kind);
  bytes[0] = static_cast<std::uint8_t>(id);
  return bytes;
}
constexpr std::uint8_t kKeyframe = 0xaa, kGraph = 0x99;

struct Sent {
  std::string channel;
  Bytes bytes;
};

// What a tracker publishes: keyframe 0, then for each k >= 1 graph k-1 and keyframe k.
KeyframeHistory published(std::int64_t keyframes) {
  KeyframeHistory history(kSlots, 1000, 500);
  for (std::int64_t k = 0; k < keyframes; ++k) {
    if (k > 0) {
      EXPECT_TRUE(history.keep_graph(kSession, k - 1, message(k - 1, kGraph), 7));
    }
    EXPECT_TRUE(history.keep_keyframe(kSession, k, message(k, kKeyframe), 7));
  }
  return history;
}

TEST(KeyframeHistory, KeepsTheLastKeyframesWithTheirGraphs) {
  const auto history = published(10);  // keyframes 6-9 held; graphs 6-8 (9's is not published yet)
  for (std::int64_t k = 0; k < 6; ++k) EXPECT_FALSE(history.find(kSession, k)) << k;
  for (std::int64_t k = 6; k < 10; ++k) {
    const auto held = history.find(kSession, k);
    ASSERT_TRUE(held) << k;
    EXPECT_EQ(Bytes(held->keyframe.bytes.begin(), held->keyframe.bytes.end()), message(k, kKeyframe));
    const Bytes graph(held->graph.bytes.begin(), held->graph.bytes.end());
    EXPECT_EQ(graph, k < 9 ? message(k, kGraph) : Bytes{}) << k;
  }
  EXPECT_FALSE(history.find(kSession + 1, 9)) << "another session's keyframe 9";
}

TEST(KeyframeHistory, AnswersWithKeyframeThenGraphAndCountsAnIdBeyondTheHistoryLostOnce) {
  auto history = published(10);
  std::vector<Sent> sent;
  const auto send = [&](const KeyframeHistory::Resend& r) {
    EXPECT_FALSE(r.slices) << "asked for whole, sent whole";
    sent.push_back(
        {r.graph ? "CVO_LOCAL_GRAPH" : "CVO_KEYFRAME", Bytes(r.message.bytes.begin(), r.message.bytes.end())});
  };
  const Ids ids{8, 2, 8, 9, 40};  // 2: no longer held; 40: never made; 8 twice
  const auto answer = history.answer(kSession, ids, {}, send);
  EXPECT_TRUE(answer.ours);
  EXPECT_EQ(answer.sent, (Ids{8, 9}));
  EXPECT_EQ(answer.lost, (Ids{2}));
  EXPECT_EQ(answer.never, (Ids{40}));
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_EQ(sent[0].channel, "CVO_KEYFRAME");
  EXPECT_EQ(sent[0].bytes, message(8, kKeyframe));
  EXPECT_EQ(sent[1].channel, "CVO_LOCAL_GRAPH");
  EXPECT_EQ(sent[1].bytes, message(8, kGraph));
  EXPECT_EQ(sent[2].channel, "CVO_KEYFRAME") << "keyframe 9 has no local graph yet";
  EXPECT_EQ(sent[2].bytes, message(9, kKeyframe));
  EXPECT_EQ(history.resent(), 2);
  EXPECT_EQ(history.lost(), 1);

  const Ids again{2, 3};
  const auto second = history.answer(kSession, again, {}, send);
  EXPECT_EQ(second.lost, (Ids{2, 3}));
  EXPECT_EQ(history.lost(), 2) << "2 was counted already: asked again, it is not lost again";
}

TEST(KeyframeHistory, AnswersARangeWithThoseSlicesOfTheMessageAndNothingOfAGraphNotPublishedYet) {
  KeyframeHistory history(kSlots, 10'000, 5'000);
  constexpr std::size_t kData = cvo_lcm::keyframe_chunk_t::MAX_DATA;
  const Bytes keyframe = message(0, kKeyframe, 3 * kData + 10);  // four slices
  ASSERT_TRUE(history.keep_keyframe(kSession, 0, keyframe, 11));
  std::vector<KeyframeHistory::Resend> sent;
  const auto send = [&](const KeyframeHistory::Resend& r) { sent.push_back(r); };
  const std::vector<KeyframeHistory::Wanted> ranges{{0, false, {2, 100}},  // slices 2 and 3: to the end
                                                    {0, true, {0, 100}},   // its graph: not published yet
                                                    {0, false, {9, 1}}};   // past its last slice
  const auto answer = history.answer(kSession, {}, ranges, send);
  EXPECT_EQ(answer.sent, (Ids{0}));
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_FALSE(sent[0].graph);
  EXPECT_EQ(sent[0].message.crc, 11u);
  EXPECT_EQ(sent[0].message.bytes.size(), keyframe.size());
  EXPECT_EQ(sent[0].slices, (lcm::SliceRange{2, 2}));
  EXPECT_EQ(history.resent(), 1);
  EXPECT_TRUE(answer.lost.empty());
}

TEST(KeyframeHistory, AnotherTrackersSessionIsNotAnswered) {
  auto history = published(5);
  int sent = 0;
  const Ids ids{0, 4};
  const auto answer = history.answer(kSession + 1, ids, {}, [&](const KeyframeHistory::Resend&) { ++sent; });
  EXPECT_FALSE(answer.ours);
  EXPECT_EQ(sent, 0);
  EXPECT_EQ(history.lost() + history.resent(), 0);
}

TEST(KeyframeHistory, AKeyframeNeverSentIsNotCountedLostAgain) {
  KeyframeHistory history(kSlots, 1000, 500);
  history.keep_keyframe(kSession, 0, message(0, kKeyframe), 7);
  history.never_sent(kSession, 1);  // dropped before publication: counted where it was dropped
  const Ids ids{1};
  const auto answer = history.answer(kSession, ids, {}, [](const KeyframeHistory::Resend&) {});
  EXPECT_EQ(answer.lost, (Ids{1}));
  EXPECT_EQ(history.lost(), 0);
}

TEST(KeyframeHistory, AMessageLargerThanItsSlotIsNotKept) {
  KeyframeHistory history(kSlots, 1000, 500);
  EXPECT_FALSE(history.keep_keyframe(kSession, 0, message(0, kKeyframe, 1001), 7));
  EXPECT_TRUE(history.keep_keyframe(kSession, 1, message(1, kKeyframe, 1000), 7));
  EXPECT_FALSE(history.keep_graph(kSession, 1, message(1, kGraph, 501), 7));
  EXPECT_TRUE(history.find(kSession, 1)->graph.bytes.empty());
  const Ids ids{0};
  EXPECT_EQ(history.answer(kSession, ids, {}, [](const KeyframeHistory::Resend&) {}).lost, (Ids{0}));
  EXPECT_EQ(history.lost(), 1);
}

TEST(KeyframeHistory, NoHistoryAnswersEveryIdLost) {
  KeyframeHistory history(0, 1000, 500);
  EXPECT_FALSE(history.keep_keyframe(kSession, 0, message(0, kKeyframe), 7));
  const Ids ids{0};
  EXPECT_EQ(history.answer(kSession, ids, {}, [](const KeyframeHistory::Resend&) {}).lost, (Ids{0}));
  EXPECT_EQ(history.lost(), 1);
}

TEST(KeyframeHistory, KeepingAllocatesNothingOnceConstructed) {
  KeyframeHistory history(kSlots, 1000, 500);
  const Bytes keyframe = message(0, kKeyframe, 1000), graph = message(0, kGraph, 500);
  history.keep_keyframe(kSession, 0, keyframe, 7);  // a session's first keyframe registers the session
  const auto before = thread_allocations();
  for (std::int64_t k = 0; k < 3 * static_cast<std::int64_t>(kSlots); ++k) {
    history.keep_keyframe(kSession, k, keyframe, 7);
    history.keep_graph(kSession, k, graph, 7);
  }
  EXPECT_EQ(thread_allocations() - before, 0);
}

}  // namespace
}  // namespace cvo::daemon::trackerd
