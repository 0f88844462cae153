// What one session and one sender may make cvo-backendd store (daemon/backendd/record_quota.hpp):
// each up to its bound, and a record past either refused with the bound it passed named.
#include <gtest/gtest.h>

#include "daemon/backendd/record_quota.hpp"

namespace cvo::daemon::backendd {
namespace {

TEST(RecordQuota, ASessionStoresUpToItsBoundAndNoMore) {
  RecordQuota quota(3, 100);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(quota.refusal(7, 1), "") << i;
    quota.count(7, 1);
  }
  const auto why = quota.refusal(7, 1);
  EXPECT_NE(why.find("3 records stored already (backendd.max_records_per_session)"), std::string::npos) << why;
  EXPECT_EQ(quota.refusal(8, 1), "") << "another session of the same sender has its own bound";
}

TEST(RecordQuota, ASenderMakingUpSessionsIsBoundedWhole) {
  RecordQuota quota(100, 5);
  for (std::int64_t session = 1; session <= 5; ++session) {
    ASSERT_EQ(quota.refusal(session, 9), "");
    quota.count(session, 9);
  }
  const auto why = quota.refusal(6, 9);
  EXPECT_NE(why.find("(backendd.max_records_per_sender)"), std::string::npos) << why;
  EXPECT_EQ(quota.refusal(6, 10), "") << "another sender is not held back by this one";
  EXPECT_EQ(quota.records_of_sender(9), 5u);
  EXPECT_EQ(quota.records_of_session(3), 1u);
}

}  // namespace
}  // namespace cvo::daemon::backendd
