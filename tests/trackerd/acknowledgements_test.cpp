// cvo-trackerd's view of what the back end holds of its sessions (daemon/trackerd/acknowledgements.hpp),
// on a clock of its own: what is waited for (keyframes ready, at or past the acknowledged prefix),
// when a keyframe not acknowledged is due to be sent again (kFirstWait after it was ready, then after
// waits that double up to kMaxWait, only while the back end is heard), what an acknowledgement removes,
// a lower prefix believed, another tracker's session ignored, and `max` bounding a round.
#include <chrono>
#include <cstdint>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/trackerd/acknowledgements.hpp"

namespace cvo::daemon::trackerd {
namespace {

using namespace std::chrono_literals;
using Clock = Acknowledgements::Clock;
using Ids = std::vector<std::int64_t>;

constexpr std::int64_t kSession = 0x5e5510'0000'0001;
constexpr std::int64_t kOther = 0x5e5510'0000'0002;
constexpr std::size_t kAll = 100;
const Clock::time_point t0{};

// Keyframes [from, to) of `session` ready (keyframe and local graph out) at `now`.
void ready(Acknowledgements& acks, std::int64_t from, std::int64_t to, Clock::time_point now,
           std::int64_t session = kSession) {
  for (std::int64_t k = from; k < to; ++k) acks.ready(session, k, now);
}

TEST(Acknowledgements, KeyframesReadyAreUnacknowledgedUntilTheBackEndSaysOtherwise) {
  Acknowledgements acks;
  EXPECT_TRUE(acks.unacknowledged(kSession).empty());
  EXPECT_EQ(acks.prefix(kSession), 0);
  EXPECT_TRUE(acks.sessions().empty());
  acks.ready(kSession, 2, t0);  // out of order, and once more: each is waited for once
  acks.ready(kSession, 0, t0);
  acks.ready(kSession, 1, t0);
  acks.ready(kSession, 1, t0);
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{0, 1, 2}));
  EXPECT_EQ(acks.prefix(kSession), 0);
  EXPECT_EQ(acks.sessions(), (Ids{kSession}));
  EXPECT_TRUE(acks.unacknowledged(kOther).empty());
}

TEST(Acknowledgements, NothingIsDueBeforeAnyAcknowledgementWasHeard) {
  Acknowledgements acks;
  ready(acks, 0, 5, t0);
  EXPECT_TRUE(acks.due(kSession, t0 + 1h, kAll).empty()) << "nobody to send to: it waits for a back end";
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{0, 1, 2, 3, 4}));
}

TEST(Acknowledgements, AKeyframeNotAcknowledgedIsDueAfterTheFirstWaitThenAfterDoublingWaitsUpToTheMaximum) {
  Acknowledgements acks;
  acks.ready(kSession, 0, t0);
  acks.ready(kSession, 1, t0);
  // The back end is heard every second from now on; it holds keyframe 0 but never 1.
  auto due = [&](Clock::time_point now) {
    acks.acknowledged(kSession, 1, now);
    return acks.due(kSession, now, kAll);
  };
  EXPECT_TRUE(due(t0 + Acknowledgements::kFirstWait - 1s).empty());
  EXPECT_EQ(due(t0 + Acknowledgements::kFirstWait), (Ids{1}));
  auto sent = t0 + Acknowledgements::kFirstWait;
  // Then after 10 s, 20 s (kMaxWait), and 20 s again: each wait doubled, capped.
  for (const std::chrono::seconds wait : {2 * Acknowledgements::kFirstWait, 4 * Acknowledgements::kFirstWait,
                                          Acknowledgements::kMaxWait, Acknowledgements::kMaxWait}) {
    EXPECT_LE(wait, Acknowledgements::kMaxWait);
    for (auto now = sent + 1s; now < sent + wait; now += 1s) EXPECT_TRUE(due(now).empty()) << "too early";
    EXPECT_EQ(due(sent + wait), (Ids{1})) << "after a wait of " << wait.count() << " s";
    sent += wait;
  }
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{1})) << "sent again is not acknowledged";
}

TEST(Acknowledgements, EachKeyframeWaitsFromWhenItBecameReady) {
  Acknowledgements acks;
  acks.ready(kSession, 0, t0);
  acks.ready(kSession, 1, t0 + 3s);
  acks.acknowledged(kSession, 0, t0 + 5s);
  EXPECT_EQ(acks.due(kSession, t0 + 5s, kAll), (Ids{0}));
  acks.acknowledged(kSession, 0, t0 + 8s);
  EXPECT_EQ(acks.due(kSession, t0 + 8s, kAll), (Ids{1}));
  EXPECT_TRUE(acks.due(kSession, t0 + 9s, kAll).empty());
}

TEST(Acknowledgements, AnAcknowledgementRemovesWhatIsBelowItsPrefix) {
  Acknowledgements acks;
  ready(acks, 0, 6, t0);
  acks.acknowledged(kSession, 4, t0 + 1s);
  EXPECT_EQ(acks.prefix(kSession), 4);
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{4, 5}));
  EXPECT_EQ(acks.due(kSession, t0 + Acknowledgements::kFirstWait, kAll), (Ids{4, 5}));

  acks.acknowledged(kSession, 6, t0 + 6s);
  EXPECT_TRUE(acks.unacknowledged(kSession).empty());
  EXPECT_TRUE(acks.due(kSession, t0 + 1h, kAll).empty());

  acks.ready(kSession, 3, t0 + 7s);  // below the prefix: held already, never waited for
  EXPECT_TRUE(acks.unacknowledged(kSession).empty());
  acks.ready(kSession, 6, t0 + 7s);
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{6}));
}

// What an acknowledgement may cover (Delivery::acknowledged takes no more): the newest keyframe
// ever ready, whatever was acknowledged since.
TEST(Acknowledgements, TheNewestKeyframeReadyIsKnownWhateverWasAcknowledged) {
  Acknowledgements acks;
  EXPECT_EQ(acks.newest(kSession), std::nullopt);
  acks.ready(kSession, 4, t0);
  acks.ready(kSession, 2, t0);
  EXPECT_EQ(acks.newest(kSession), 4);
  acks.acknowledged(kSession, 5, t0 + 1s);
  EXPECT_EQ(acks.newest(kSession), 4);
  EXPECT_EQ(acks.newest(kOther), std::nullopt);
}

TEST(Acknowledgements, ALowerPrefixLaterIsBelievedButWhatWasAcknowledgedIsNotWaitedForAgain) {
  Acknowledgements acks;
  ready(acks, 0, 10, t0);
  acks.acknowledged(kSession, 8, t0 + 1s);
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{8, 9}));

  // A back end that restarted without its store: it holds keyframes 0-1 only (its newest word counts).
  acks.acknowledged(kSession, 2, t0 + 2s);
  EXPECT_EQ(acks.prefix(kSession), 2);
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{8, 9})) << "2-7 were forgotten at the first acknowledgement";
  EXPECT_EQ(acks.due(kSession, t0 + 5s, kAll), (Ids{8, 9}));

  // Keyframes ready from now on are waited for from the lower prefix on.
  acks.ready(kSession, 5, t0 + 3s);
  acks.ready(kSession, 1, t0 + 3s);
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{5, 8, 9}));
}

TEST(Acknowledgements, NothingIsDueWhenTheBackEndWasLastHeardLongerAgoThanAlive) {
  Acknowledgements acks;
  ready(acks, 0, 3, t0);
  acks.acknowledged(kSession, 1, t0 + 10s);
  const auto silent = t0 + 10s + Acknowledgements::kAlive;
  EXPECT_EQ(acks.due(kSession, silent, kAll), (Ids{1, 2})) << "heard kAlive ago: still there";
  EXPECT_TRUE(acks.due(kSession, silent + 1h, kAll).empty()) << "not heard for an hour";
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{1, 2})) << "still waited for";

  acks.acknowledged(kSession, 1, t0 + 2h);  // heard again: what is due goes out at once
  EXPECT_EQ(acks.due(kSession, t0 + 2h, kAll), (Ids{1, 2}));
}

TEST(Acknowledgements, AcknowledgementsOfSessionsNotOursAreIgnored) {
  Acknowledgements acks;
  ready(acks, 0, 3, t0);
  acks.acknowledged(kOther, 5, t0 + 1s);  // another tracker's session
  EXPECT_EQ(acks.sessions(), (Ids{kSession}));
  EXPECT_EQ(acks.prefix(kOther), 0);
  EXPECT_TRUE(acks.unacknowledged(kOther).empty());
  EXPECT_TRUE(acks.due(kOther, t0 + 1h, kAll).empty());
  EXPECT_TRUE(acks.due(kSession, t0 + Acknowledgements::kFirstWait, kAll).empty())
      << "the other session's acknowledgement is not ours: our back end was never heard";
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{0, 1, 2}));
}

TEST(Acknowledgements, SessionsAreWaitedForEachOnItsOwn) {
  Acknowledgements acks;
  ready(acks, 0, 3, t0, kSession);
  ready(acks, 0, 3, t0, kOther);
  acks.acknowledged(kSession, 2, t0 + 1s);
  EXPECT_EQ(acks.unacknowledged(kSession), (Ids{2}));
  EXPECT_EQ(acks.unacknowledged(kOther), (Ids{0, 1, 2}));
  EXPECT_EQ(acks.due(kSession, t0 + 5s, kAll), (Ids{2}));
  EXPECT_TRUE(acks.due(kOther, t0 + 5s, kAll).empty()) << "its back end was never heard of it";
  EXPECT_EQ(acks.sessions(), (Ids{kSession, kOther}));
}

TEST(Acknowledgements, MaxBoundsARoundAndTheRestFollowInTheNext) {
  Acknowledgements acks;
  ready(acks, 0, 5, t0);
  acks.acknowledged(kSession, 0, t0 + 5s);
  EXPECT_EQ(acks.due(kSession, t0 + 5s, 2), (Ids{0, 1}));
  EXPECT_EQ(acks.due(kSession, t0 + 5s, 2), (Ids{2, 3}));
  EXPECT_EQ(acks.due(kSession, t0 + 5s, 2), (Ids{4}));
  EXPECT_TRUE(acks.due(kSession, t0 + 5s, 2).empty());
  EXPECT_TRUE(acks.due(kSession, t0 + 5s, 0).empty());
}

}  // namespace
}  // namespace cvo::daemon::trackerd
