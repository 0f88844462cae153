// What CVO_KEYFRAME_REQUESTs may make cvo-trackerd send again (daemon/trackerd/resend_budget.hpp):
// a second's worth at once, then the rate; per requester and per session; a message larger than a
// second's worth still goes out from a full bucket; and the keyframe history's answer keeps over
// budget what it does not send.
#include <cstdint>
#include <span>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/trackerd/keyframe_history.hpp"
#include "daemon/trackerd/resend_budget.hpp"

namespace cvo::daemon::trackerd {
namespace {

constexpr double kRate = 1000;  // bytes a second
constexpr std::int64_t kSession = 7;

TEST(ResendBudget, ASecondsWorthGoesAtOnceThenTheRate) {
  ResendBudget budget(kRate);
  int sent = 0;
  for (int i = 0; i < 50; ++i) sent += budget.take(1, kSession, 100, 0.0) ? 1 : 0;
  EXPECT_EQ(sent, 10) << "the burst: one second's worth";
  EXPECT_EQ(budget.refused(), 40);
  EXPECT_FALSE(budget.take(1, kSession, 100, 0.05)) << "refilled 50 bytes only";
  EXPECT_TRUE(budget.take(1, kSession, 100, 0.1));
  // Over ten seconds of requests every 10 ms, at most rate · t + a second's worth goes out.
  ResendBudget steady(kRate);
  double bytes = 0;
  for (int i = 0; i <= 1000; ++i) bytes += steady.take(1, kSession, 100, i * 0.01) ? 100 : 0;
  EXPECT_LE(bytes, kRate * 10 + kRate);
  EXPECT_GE(bytes, kRate * 10);
}

TEST(ResendBudget, ASessionsBudgetIsSharedByItsRequestersAndARequestersByItsSessions) {
  ResendBudget budget(kRate);
  EXPECT_TRUE(budget.take(1, kSession, 600, 0));
  EXPECT_FALSE(budget.take(2, kSession, 600, 0)) << "another requester, the same session: 400 left";
  EXPECT_TRUE(budget.take(2, kSession + 1, 600, 0)) << "another requester and session: their own buckets";
  EXPECT_FALSE(budget.take(1, kSession + 2, 600, 0)) << "requester 1 has 400 left, whatever the session";
}

TEST(ResendBudget, AMessageLargerThanASecondsWorthGoesFromAFullBucketAndIsPaidOff) {
  ResendBudget budget(kRate);
  EXPECT_TRUE(budget.take(1, kSession, 5000, 0));
  EXPECT_FALSE(budget.take(1, kSession, 100, 3.0)) << "still paying off the 4000 bytes of debt";
  EXPECT_TRUE(budget.take(1, kSession, 100, 4.2));
}

TEST(ResendBudget, ForgetsTheLeastRecentlySeenRequesterFirst) {
  ResendBudget budget(kRate);
  ASSERT_TRUE(budget.take(0, kSession, 1000, 0));  // requester 0 has spent its second
  for (std::uint64_t r = 1; r <= 15; ++r) ASSERT_TRUE(budget.take(r, 100 + static_cast<std::int64_t>(r), 1, 1e-3 * r));
  EXPECT_FALSE(budget.take(0, 200, 1000, 0.02)) << "requester 0 is still known (16 held)";
  ASSERT_TRUE(budget.take(16, 116, 1, 0.03));  // the 17th: requester 1, least recent, goes
  EXPECT_FALSE(budget.take(0, 201, 1000, 0.04)) << "requester 0 was seen more recently than 1: kept";
}

TEST(KeyframeHistory, AnAnswerOverBudgetSendsNothingOfTheKeyframesItCannotAfford) {
  KeyframeHistory history(4, 1000, 500);
  for (std::int64_t k = 0; k < 4; ++k) {
    history.made(kSession, k);
    ASSERT_TRUE(history.keep_keyframe(kSession, k, std::vector<std::uint8_t>(300, 1), 7));
  }
  ResendBudget budget(kRate);
  int sent = 0;
  const auto send = [&](const KeyframeHistory::Resend&) { ++sent; };
  const auto afford = [&](std::size_t bytes) { return budget.take(0, kSession, bytes, 0); };
  const std::vector<std::int64_t> ids{0, 1, 2, 3};
  const auto answer = history.answer(kSession, ids, {}, send, afford);
  EXPECT_EQ(answer.sent, (std::vector<std::int64_t>{0, 1, 2}));
  EXPECT_EQ(answer.over, (std::vector<std::int64_t>{3}));
  EXPECT_EQ(sent, 3);
  EXPECT_EQ(history.resent(), 3);
  EXPECT_EQ(history.lost(), 0) << "over budget is not lost: a later request has it";
}

}  // namespace
}  // namespace cvo::daemon::trackerd
