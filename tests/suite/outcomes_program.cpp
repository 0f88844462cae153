// A test program of each outcome, run by skip_rules_test.cpp with --gtest_filter to see which exit
// status tests/support/test_main.cpp gives each mix. Never registered with CTest itself.
#include <gtest/gtest.h>

TEST(Outcome, Passes) { SUCCEED(); }

TEST(Outcome, SkipsForAReason) { GTEST_SKIP() << "needs a camera that is not here"; }

TEST(Outcome, Fails) { ADD_FAILURE() << "a failure"; }
