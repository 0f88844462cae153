// The back end's bookkeeping of keyframes lost in transport (daemon/backendd/keyframe_gaps.hpp), on
// a clock of its own: what is missing after each kind of message, when it is asked for, how often,
// when it is given up, and what is counted.
#include <chrono>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/backendd/keyframe_gaps.hpp"

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;
using Seen = KeyframeGaps::Seen;
using Clock = KeyframeGaps::Clock;
using Ids = std::vector<std::int64_t>;

constexpr std::int64_t kSession = 0x5e5510'0000'0001;
const Clock::time_point t0{};

// A tracker's output in order: local graph k-1, then keyframe k, for k in [from, to).
void send(KeyframeGaps& gaps, std::int64_t from, std::int64_t to, Clock::time_point now,
          std::int64_t session = kSession) {
  for (std::int64_t k = from; k < to; ++k) {
    if (k > 0) gaps.seen(Seen::kLocalGraph, session, k - 1, now);
    gaps.seen(Seen::kKeyframe, session, k, now);
  }
}

// The ids asked of `session` in a round (empty: none).
Ids asked(const KeyframeGaps::Round& round, std::int64_t session = kSession) {
  for (const auto& r : round.requests)
    if (r.session == session) return r.ids;
  return {};
}

TEST(KeyframeGaps, AnUnbrokenSessionAsksForNothing) {
  KeyframeGaps gaps;
  send(gaps, 0, 20, t0);
  gaps.seen(Seen::kPose, kSession, 19, t0);
  const auto round = gaps.due(t0 + 1h);
  EXPECT_TRUE(round.requests.empty());
  EXPECT_TRUE(round.given_up.empty());
  EXPECT_EQ(gaps.missing(), 0u);
  EXPECT_EQ(gaps.requested() + gaps.recovered() + gaps.lost(), 0);
}

TEST(KeyframeGaps, AKeyframeAboveTheNextExpectedOneAsksForThoseBetween) {
  KeyframeGaps gaps;
  send(gaps, 0, 3, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 2, t0);
  gaps.seen(Seen::kKeyframe, kSession, 5, t0);  // 3 and 4 (and their graphs) never came
  EXPECT_EQ(gaps.missing(), 2u);
  EXPECT_TRUE(gaps.due(t0 + 499ms).requests.empty()) << "a late message is waited for first";
  EXPECT_EQ(asked(gaps.due(t0 + 500ms)), (Ids{3, 4}));
  EXPECT_EQ(gaps.requested(), 2);

  // The tracker answers keyframe then graph: recovered once both are there.
  gaps.seen(Seen::kKeyframe, kSession, 3, t0 + 110ms);
  gaps.seen(Seen::kLocalGraph, kSession, 3, t0 + 110ms);
  gaps.seen(Seen::kKeyframe, kSession, 4, t0 + 110ms);
  EXPECT_EQ(gaps.recovered(), 1) << "keyframe 4's graph has not come yet";
  gaps.seen(Seen::kLocalGraph, kSession, 4, t0 + 110ms);
  EXPECT_EQ(gaps.recovered(), 2);
  EXPECT_EQ(gaps.missing(), 0u);
  EXPECT_TRUE(gaps.due(t0 + 1h).requests.empty());
  EXPECT_EQ(gaps.lost(), 0);
}

TEST(KeyframeGaps, WhatCameLateBeforeTheFirstRequestIsNeitherAskedNorCounted) {
  KeyframeGaps gaps;
  send(gaps, 0, 2, t0);
  gaps.seen(Seen::kKeyframe, kSession, 3, t0);  // graph 1 and keyframe 2 overtaken
  gaps.seen(Seen::kLocalGraph, kSession, 1, t0 + 50ms);
  gaps.seen(Seen::kKeyframe, kSession, 2, t0 + 50ms);
  gaps.seen(Seen::kLocalGraph, kSession, 2, t0 + 50ms);
  EXPECT_TRUE(gaps.due(t0 + 1h).requests.empty());
  EXPECT_EQ(gaps.requested() + gaps.recovered() + gaps.lost(), 0);
}

TEST(KeyframeGaps, AMissingLocalGraphIsAskedForByItsKeyframe) {
  KeyframeGaps gaps;
  gaps.seen(Seen::kKeyframe, kSession, 0, t0);
  gaps.seen(Seen::kKeyframe, kSession, 1, t0);  // graph 0 went out before it, and never came
  EXPECT_EQ(asked(gaps.due(t0 + 1s)), (Ids{0}));
  gaps.seen(Seen::kLocalGraph, kSession, 0, t0 + 2s);  // keyframe 0 again is a repeat: not seen
  EXPECT_EQ(gaps.recovered(), 1);
}

TEST(KeyframeGaps, ALocalGraphWhoseKeyframeNeverCameAsksForBoth) {
  KeyframeGaps gaps;
  send(gaps, 0, 5, t0);                                     // keyframes 0-4, graphs 0-3
  gaps.seen(Seen::kGraphWithoutKeyframe, kSession, 5, t0);  // keyframe 5 lost, its graph refused
  EXPECT_EQ(asked(gaps.due(t0 + 1s)), (Ids{4, 5})) << "graph 4 went out before keyframe 5";
  gaps.seen(Seen::kKeyframe, kSession, 4, t0 + 1s);  // repeats are not seen; these are the answers
  gaps.seen(Seen::kLocalGraph, kSession, 4, t0 + 1s);
  gaps.seen(Seen::kKeyframe, kSession, 5, t0 + 1s);
  EXPECT_EQ(gaps.recovered(), 1) << "keyframe 5's refused graph is still needed";
  gaps.seen(Seen::kLocalGraph, kSession, 5, t0 + 1s);
  EXPECT_EQ(gaps.recovered(), 2);
  EXPECT_EQ(gaps.missing(), 0u);
}

TEST(KeyframeGaps, APoseNamesItsKeyframe) {
  KeyframeGaps gaps;
  send(gaps, 0, 3, t0);
  gaps.seen(Seen::kPose, kSession, 3, t0);  // the session's newest keyframe never came
  EXPECT_EQ(asked(gaps.due(t0 + 1s)), (Ids{2, 3}));
}

TEST(KeyframeGaps, AsksAgainWithBackOffThenGivesUpAndCountsItLost) {
  GapPolicy policy;
  policy.first_wait = 100ms;
  policy.retry_wait = 500ms;
  policy.requests = 3;
  policy.alive_window = 2s;
  KeyframeGaps gaps(policy);
  send(gaps, 0, 2, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 1, t0);
  gaps.seen(Seen::kKeyframe, kSession, 3, t0);
  EXPECT_EQ(asked(gaps.due(t0 + 100ms)), (Ids{2}));  // 1st
  EXPECT_TRUE(gaps.due(t0 + 599ms).requests.empty());
  EXPECT_EQ(asked(gaps.due(t0 + 600ms)), (Ids{2}));  // 2nd, 500 ms later
  EXPECT_TRUE(gaps.due(t0 + 1599ms).requests.empty());
  EXPECT_EQ(asked(gaps.due(t0 + 1600ms)), (Ids{2}));  // 3rd, 1 s later
  const auto before = gaps.due(t0 + 3599ms);
  EXPECT_TRUE(before.requests.empty());
  EXPECT_TRUE(before.given_up.empty());
  const auto round = gaps.due(t0 + 3600ms);  // 2 s after the last
  EXPECT_TRUE(round.requests.empty());
  ASSERT_EQ(round.given_up.size(), 1u);
  EXPECT_EQ(round.given_up[0].session, kSession);
  EXPECT_EQ(round.given_up[0].first, 2);
  EXPECT_EQ(round.given_up[0].last, 2);
  EXPECT_EQ(round.given_up[0].reason, KeyframeGaps::GivenUp::Reason::kSilent) << "nothing heard since t0";
  EXPECT_EQ(gaps.requested(), 1) << "one keyframe asked for, however often";
  EXPECT_EQ(gaps.lost(), 1);
  EXPECT_EQ(gaps.recovered(), 0);
  gaps.seen(Seen::kKeyframe, kSession, 2, t0 + 4s);  // too late: it stays counted lost, not recovered
  EXPECT_EQ(gaps.recovered(), 0);
  EXPECT_TRUE(gaps.due(t0 + 1h).requests.empty());
}

// Issue 28: past its `requests`, the back end keeps asking while the session's tracker is heard
// (its poses), every max_retry_wait at most, and gives up once it is silent, saying so.
TEST(KeyframeGaps, KeepsAskingWithBackOffWhileItsTrackerIsHeard) {
  GapPolicy policy;
  policy.first_wait = 100ms;
  policy.requests = 3;
  KeyframeGaps gaps(policy);
  send(gaps, 0, 2, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 1, t0);
  gaps.seen(Seen::kKeyframe, kSession, 3, t0);  // keyframe 2 lost
  std::vector<Clock::time_point> asked_at;
  Clock::time_point now = t0;
  for (; now < t0 + 30s; now += 100ms) {
    gaps.seen(Seen::kPose, kSession, 3, now);  // the tracker runs: a pose every 100 ms
    if (!asked(gaps.due(now)).empty()) asked_at.push_back(now);
  }
  ASSERT_GE(asked_at.size(), 8u) << "asked again for as long as the tracker runs";
  EXPECT_EQ(asked_at[0], t0 + 100ms);
  EXPECT_EQ(asked_at[1] - asked_at[0], 500ms);
  EXPECT_EQ(asked_at[2] - asked_at[1], 1s);
  EXPECT_EQ(asked_at[3] - asked_at[2], 2s);
  for (std::size_t i = 4; i < asked_at.size(); ++i) EXPECT_EQ(asked_at[i] - asked_at[i - 1], 4s) << "capped";
  EXPECT_EQ(gaps.lost(), 0);
  // The tracker falls silent: once asking is due again and nothing was heard for alive_window.
  std::vector<KeyframeGaps::GivenUp> given_up;
  for (; given_up.empty() && now < t0 + 60s; now += 100ms) given_up = gaps.due(now).given_up;
  ASSERT_EQ(given_up.size(), 1u);
  EXPECT_EQ(given_up[0].first, 2);
  EXPECT_EQ(given_up[0].reason, KeyframeGaps::GivenUp::Reason::kSilent);
  EXPECT_EQ(gaps.lost(), 1);
}

// A tracker that runs but never answers (it no longer holds the keyframe) is asked for
// give_up_after from the first request, not for ever.
TEST(KeyframeGaps, GivesUpOnATrackerThatRunsButNeverAnswers) {
  GapPolicy policy;
  policy.give_up_after = 20s;
  KeyframeGaps gaps(policy);
  send(gaps, 0, 2, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 1, t0);
  gaps.seen(Seen::kKeyframe, kSession, 3, t0);
  std::vector<KeyframeGaps::GivenUp> given_up;
  Clock::time_point now = t0;
  for (; given_up.empty() && now < t0 + 60s; now += 100ms) {
    gaps.seen(Seen::kPose, kSession, 3, now);
    given_up = gaps.due(now).given_up;
  }
  ASSERT_EQ(given_up.size(), 1u);
  EXPECT_EQ(given_up[0].reason, KeyframeGaps::GivenUp::Reason::kUnanswered);
  EXPECT_GE(now - t0, 20s);
  EXPECT_LE(now - t0, 25s);
}

// A keyframe that comes in slices over a lossy link: each answer brings part of it, which restarts
// the back-off and puts the next request just after the answer's burst; asking goes on for as long
// as parts come, however long that is, and stops give_up_after once nothing more does.
TEST(KeyframeGaps, EachPartThatComesRestartsTheBackOffAndTheTimeToGiveUp) {
  GapPolicy policy;
  policy.first_wait = 100ms;
  policy.give_up_after = 10s;
  KeyframeGaps gaps(policy);
  send(gaps, 0, 2, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 1, t0);
  gaps.seen(Seen::kKeyframe, kSession, 3, t0);  // keyframe 2 came in part
  Clock::time_point now = t0 + 100ms;
  ASSERT_EQ(asked(gaps.due(now)), (Ids{2}));
  for (int round = 0; round < 20; ++round) {  // 20 answers, each bringing a part 50 ms after asking
    gaps.progressed(kSession, 2, now + 50ms);
    EXPECT_TRUE(gaps.due(now + 149ms).requests.empty()) << "the burst of the answer is waited out";
    now += 150ms;
    ASSERT_EQ(asked(gaps.due(now)), (Ids{2})) << "asked again at once, not after a doubled wait: round " << round;
  }
  EXPECT_GT(now - t0, 3s);
  // Nothing more comes: the back-off doubles again, and asking stops give_up_after the last part.
  std::vector<KeyframeGaps::GivenUp> given_up;
  for (; given_up.empty() && now < t0 + 60s; now += 100ms) {
    gaps.seen(Seen::kPose, kSession, 3, now);  // the tracker runs
    given_up = gaps.due(now).given_up;
  }
  ASSERT_EQ(given_up.size(), 1u);
  EXPECT_EQ(given_up[0].reason, KeyframeGaps::GivenUp::Reason::kUnanswered);
  EXPECT_GE(now - (t0 + 100ms + 20 * 150ms), 10s);
  EXPECT_EQ(gaps.requested(), 1);
}

// A slice of a session's newest local graph (sent as the tracker stops, nothing after it to name
// it) says the graph exists: the rest is asked for.
TEST(KeyframeGaps, ASliceOfALocalGraphAsksForTheRestOfIt) {
  KeyframeGaps gaps;
  send(gaps, 0, 3, t0);  // keyframes 0-2, graphs 0-1
  gaps.seen(Seen::kGraphPart, kSession, 2, t0);
  const auto round = gaps.due(t0 + 1s);
  ASSERT_EQ(round.requests.size(), 1u);
  EXPECT_EQ(round.requests[0].ids, (Ids{2}));
  EXPECT_EQ(round.requests[0].graphs_only, (Ids{2})) << "its keyframe came: the graph alone is asked for";
}

TEST(KeyframeGaps, TheGraphOfAKeyframeGivenUpIsNotCountedAgain) {
  GapPolicy policy;
  policy.requests = 1;
  policy.alive_window = 2s;
  KeyframeGaps gaps(policy);
  send(gaps, 0, 3, t0);
  gaps.seen(Seen::kPose, kSession, 3, t0);  // keyframe 3 lost (and graph 2)
  EXPECT_EQ(asked(gaps.due(t0 + 1s)), (Ids{2, 3}));
  gaps.seen(Seen::kLocalGraph, kSession, 2, t0 + 1s);
  EXPECT_EQ(gaps.due(t0 + 3500ms).given_up.size(), 1u);  // keyframe 3: never came, the tracker silent
  EXPECT_EQ(gaps.lost(), 1);
  gaps.seen(Seen::kGraphWithoutKeyframe, kSession, 3, t0 + 4s);  // its graph at the session's end
  gaps.seen(Seen::kKeyframe, kSession, 4, t0 + 4s);              // and the session goes on
  gaps.seen(Seen::kLocalGraph, kSession, 4, t0 + 4s);
  gaps.seen(Seen::kKeyframe, kSession, 5, t0 + 4s);
  EXPECT_TRUE(gaps.due(t0 + 1h).given_up.empty());
  EXPECT_EQ(gaps.give_up_all().size(), 0u);
  EXPECT_EQ(gaps.lost(), 1);
  EXPECT_EQ(gaps.recovered(), 1);  // graph 2
}

TEST(KeyframeGaps, EachRoundAsksForAFewKeyframesAtMost) {
  GapPolicy policy;
  policy.ids_per_round = 4;
  policy.round_interval = 100ms;
  KeyframeGaps gaps(policy);
  gaps.seen(Seen::kKeyframe, kSession, 0, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 0, t0);
  gaps.seen(Seen::kKeyframe, kSession, 11, t0);  // 1..10 missing
  EXPECT_EQ(asked(gaps.due(t0 + 1s)), (Ids{1, 2, 3, 4}));
  EXPECT_TRUE(gaps.due(t0 + 1s + 99ms).requests.empty()) << "one round per interval";
  EXPECT_EQ(asked(gaps.due(t0 + 1s + 100ms)), (Ids{5, 6, 7, 8}));
  EXPECT_EQ(asked(gaps.due(t0 + 1s + 200ms)), (Ids{9, 10}));
  EXPECT_EQ(gaps.requested(), 10);
  EXPECT_EQ(gaps.lost(), 0) << "waiting for a round is no request and no loss";
}

TEST(KeyframeGaps, ARecordingIsNeverAskedItsGapsAreLostAtOnce) {
  GapPolicy policy;
  policy.requests = 0;
  KeyframeGaps gaps(policy);
  gaps.seen(Seen::kKeyframe, kSession, 0, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 0, t0);
  gaps.seen(Seen::kKeyframe, kSession, 2, t0);
  const auto round = gaps.due(t0 + 1s);
  EXPECT_TRUE(round.requests.empty());
  ASSERT_EQ(round.given_up.size(), 1u);
  EXPECT_EQ(round.given_up[0].first, 1);
  EXPECT_EQ(round.given_up[0].reason, KeyframeGaps::GivenUp::Reason::kNoAsking);
  EXPECT_EQ(gaps.requested(), 0);
  EXPECT_EQ(gaps.lost(), 1);
}

TEST(KeyframeGaps, AStopGivesUpWhatIsStillWaitedFor) {
  KeyframeGaps gaps;
  send(gaps, 0, 2, t0);
  gaps.seen(Seen::kKeyframe, kSession, 5, t0);  // graph 1, keyframes 2-4
  ASSERT_EQ(asked(gaps.due(t0 + 1s)).size(), 4u);
  const auto given_up = gaps.give_up_all();
  ASSERT_EQ(given_up.size(), 1u);
  EXPECT_EQ(given_up[0].first, 1);
  EXPECT_EQ(given_up[0].last, 4);
  EXPECT_EQ(given_up[0].reason, KeyframeGaps::GivenUp::Reason::kStopped);
  EXPECT_EQ(gaps.lost(), 4);
  EXPECT_EQ(gaps.missing(), 0u);
}

TEST(KeyframeGaps, SessionsAreKeptApart) {
  constexpr std::int64_t kOther = -0x2222'3333'4444'5555;
  KeyframeGaps gaps;
  send(gaps, 0, 3, t0);
  send(gaps, 0, 2, t0, kOther);
  gaps.seen(Seen::kLocalGraph, kOther, 1, t0);
  gaps.seen(Seen::kKeyframe, kOther, 3, t0);  // kOther's 2 is missing, nothing of kSession
  const auto round = gaps.due(t0 + 1s);
  EXPECT_EQ(asked(round, kOther), (Ids{2}));
  EXPECT_TRUE(asked(round, kSession).empty());
  gaps.seen(Seen::kKeyframe, kSession, 2, t0 + 1s);  // a repeat of kSession's: changes nothing
  EXPECT_EQ(gaps.recovered(), 0);
}

TEST(KeyframeGaps, AForgedIdAsksOnlyForTheNewestAndGivesUpTheRest) {
  GapPolicy policy;
  policy.max_gap = 8;
  policy.ids_per_round = 16;
  KeyframeGaps gaps(policy);
  gaps.seen(Seen::kKeyframe, kSession, 0, t0);
  gaps.seen(Seen::kLocalGraph, kSession, 0, t0);
  constexpr std::int64_t kForged = std::int64_t{1} << 50;
  gaps.seen(Seen::kKeyframe, kSession, kForged, t0);
  EXPECT_EQ(gaps.missing(), 8u);
  const auto round = gaps.due(t0 + 1s);
  ASSERT_EQ(asked(round).size(), 8u);
  EXPECT_EQ(asked(round).front(), kForged - 8);
  ASSERT_EQ(round.given_up.size(), 1u);
  EXPECT_EQ(round.given_up[0].first, 1);
  EXPECT_EQ(round.given_up[0].last, kForged - 9);
  EXPECT_EQ(round.given_up[0].reason, KeyframeGaps::GivenUp::Reason::kBounds);
  EXPECT_EQ(gaps.lost(), kForged - 9);
}

TEST(KeyframeGaps, MemoryIsBoundedAgainstManySessions) {
  GapPolicy policy;
  policy.max_sessions = 2;
  policy.max_missing = 3;
  KeyframeGaps gaps(policy);
  gaps.seen(Seen::kKeyframe, 1, 2, t0);       // session 1: keyframes 0, 1 and graphs 0, 1 missing
  gaps.seen(Seen::kKeyframe, 2, 2, t0 + 1s);  // session 2: one fits, one given up at once
  EXPECT_EQ(gaps.missing(), 3u);
  EXPECT_EQ(gaps.lost(), 1);
  gaps.seen(Seen::kKeyframe, 3, 0, t0 + 2s);  // a third session: session 1, least recently seen, forgotten
  EXPECT_EQ(gaps.missing(), 1u);
  EXPECT_EQ(gaps.lost(), 3);
  const auto round = gaps.due(t0 + 3s);
  EXPECT_TRUE(asked(round, 1).empty());
  EXPECT_EQ(asked(round, 2), (Ids{0}));
}

}  // namespace
}  // namespace cvo::daemon::backendd
