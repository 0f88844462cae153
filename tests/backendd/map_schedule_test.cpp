// When cvo-backendd's map goes out (daemon/backendd/map_schedule.hpp): a session's correction when
// its entry changed, and again once a period while it is live; the full map at once after a join,
// a second after the last one after a loop closure, else at most once its period while changes
// wait, and after every change with a period of 0. Time is given, so nothing here waits.
#include <gtest/gtest.h>

#include "daemon/backendd/map_schedule.hpp"

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;
const MapSchedule::Clock::time_point t0{};

TEST(MapSchedule, ACorrectionGoesWhenItsEntryChanged) {
  MapSchedule schedule({5s, 1s, 10s});
  const std::vector<std::uint8_t> a{1, 2, 3}, b{1, 2, 4};
  EXPECT_TRUE(schedule.differs(7, a)) << "never sent";
  schedule.sent(7, a, t0);
  EXPECT_FALSE(schedule.differs(7, a)) << "the same entry again: nothing to send";
  EXPECT_TRUE(schedule.differs(7, b));
  EXPECT_TRUE(schedule.differs(8, a)) << "another session's is its own";
}

// A lingering tracker waits for its acknowledgement: it goes as soon as more is held than the last
// correction said, whether a correction of the session went before or not.
TEST(MapSchedule, ACorrectionGoesAtOnceWhenMoreIsHeldThanItAcknowledged) {
  MapSchedule schedule({5s, 1s, 10s});
  EXPECT_TRUE(schedule.acknowledgements_due({{7, 0}}).empty()) << "nothing held: nothing to say";
  EXPECT_EQ(schedule.acknowledgements_due({{7, 2}}), std::vector<std::int64_t>{7}) << "none sent yet";
  schedule.sent(7, {1}, t0, 2);
  EXPECT_TRUE(schedule.acknowledgements_due({{7, 2}}).empty()) << "said already";
  EXPECT_EQ(schedule.acknowledgements_due({{7, 3}, {8, 1}}), (std::vector<std::int64_t>{7, 8}));
}

TEST(MapSchedule, ALiveSessionsCorrectionGoesAgainOnceAPeriod) {
  MapSchedule schedule({5s, 1s, 10s});
  schedule.sent(7, {1}, t0);
  schedule.sent(8, {2}, t0);
  schedule.seen(7, t0);
  schedule.seen(9, t0);  // live, but no correction of it went yet: nothing to repeat
  EXPECT_TRUE(schedule.resends_due(t0 + 500ms).empty());
  EXPECT_EQ(schedule.resends_due(t0 + 1s), std::vector<std::int64_t>{7}) << "8 is not live";
  schedule.sent(7, {1}, t0 + 1s);
  EXPECT_TRUE(schedule.resends_due(t0 + 1500ms).empty());
  EXPECT_EQ(schedule.resends_due(t0 + 2s), std::vector<std::int64_t>{7});
  EXPECT_TRUE(schedule.resends_due(t0 + 11s).empty()) << "nothing heard of it for 10 s: no longer live";
  schedule.seen(8, t0 + 12s);
  EXPECT_EQ(schedule.resends_due(t0 + 12s), std::vector<std::int64_t>{8});
  schedule.lost(8);
  EXPECT_TRUE(schedule.resends_due(t0 + 12s).empty()) << "a lost session's tracker has moved on";
}

TEST(MapSchedule, AfterAnOptimisationOnlyTheLiveSessionsAreOffered) {
  MapSchedule schedule({5s, 1s, 10s});
  schedule.seen(7, t0);
  schedule.seen(8, t0 + 5s);
  const std::vector<std::int64_t> sessions{7, 8, 9};  // 9: never heard of (a stored session's)
  EXPECT_EQ(schedule.live(sessions, t0 + 10s), (std::vector<std::int64_t>{7, 8}));
  EXPECT_EQ(schedule.live(sessions, t0 + 12s), std::vector<std::int64_t>{8}) << "7 silent for 12 s";
  schedule.lost(8);
  EXPECT_TRUE(schedule.live(sessions, t0 + 12s).empty()) << "a lost session's tracker has moved on";
}

TEST(MapSchedule, TheFullMapGoesAtOnceAfterAJoinElseAtMostOnceAPeriod) {
  MapSchedule schedule({5s, 1s, 10s, 1s});
  EXPECT_FALSE(schedule.map_due(t0, true)) << "nothing changed";
  schedule.changed();
  EXPECT_TRUE(schedule.map_due(t0, false)) << "the first map at once";
  schedule.map_sent(t0);
  schedule.changed();
  EXPECT_FALSE(schedule.map_due(t0 + 1s, false));
  EXPECT_FALSE(schedule.map_due(t0 + 4900ms, false));
  EXPECT_TRUE(schedule.map_due(t0 + 1s, true)) << "a join";
  EXPECT_TRUE(schedule.map_due(t0 + 5s, false)) << "the period passed while a change waited";
  schedule.map_sent(t0 + 5s);
  EXPECT_FALSE(schedule.map_due(t0 + 20s, false)) << "no change since: no map";
}

TEST(MapSchedule, ALoopClosuresMapGoesASecondAfterTheLastNotAfterEveryKeyframe) {
  MapSchedule schedule({5s, 1s, 10s, 1s});
  schedule.changed();
  schedule.map_sent(t0);
  schedule.changed(true);
  EXPECT_TRUE(schedule.loop_waiting());
  EXPECT_FALSE(schedule.map_due(t0 + 300ms, false)) << "a loop within a second of the last map waits";
  schedule.changed(true);
  schedule.changed();
  EXPECT_TRUE(schedule.map_due(t0 + 1s, false)) << "the loops' map goes once the second has passed";
  schedule.map_sent(t0 + 1s);
  EXPECT_FALSE(schedule.loop_waiting()) << "that map had the loops";
  schedule.changed();
  EXPECT_FALSE(schedule.map_due(t0 + 2500ms, false)) << "a change without a loop waits for the period";
}

TEST(MapSchedule, WithAPeriodOfZeroTheMapGoesAfterEveryChange) {
  MapSchedule schedule({0s, 1s, 10s});
  for (int i = 0; i < 3; ++i) {
    schedule.changed();
    EXPECT_TRUE(schedule.map_due(t0, false)) << i;
    schedule.map_sent(t0);
  }
}

}  // namespace
}  // namespace cvo::daemon::backendd
