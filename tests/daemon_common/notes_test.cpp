// Notes: one log-rate policy for both daemons (a kind of note at most once a period, the next one
// counting what was held back), and the last note for CVO_STATUS's detail.
#include "daemon/common/notes.hpp"

#include <thread>

#include <gtest/gtest.h>

namespace cvo::daemon {
namespace {

TEST(Notes, AFloodOfOneKindIsWrittenOnceAPeriodAndCountsWhatWasHeldBack) {
  Notes notes("test");
  testing::internal::CaptureStderr();
  notes.note_limited("bad", "bad message #1");
  for (int i = 2; i <= 50; ++i) notes.note_limited("bad", "bad message #" + std::to_string(i));
  notes.note_limited("other", "another kind is not held back");
  std::this_thread::sleep_for(Notes::period + std::chrono::milliseconds(50));
  notes.note_limited("bad", "bad message #51");
  const std::string log = testing::internal::GetCapturedStderr();
  EXPECT_EQ(log,
            "test: bad message #1\n"
            "test: another kind is not held back\n"
            "test: bad message #51 (and 49 like it not shown)\n");
  EXPECT_EQ(notes.last(), "bad message #51 (and 49 like it not shown)");
}

TEST(Notes, EveryPlainNoteIsWrittenAndTheLastIsKeptForTheStatus) {
  Notes notes("cvo-x");
  testing::internal::CaptureStderr();
  notes.note("one");
  notes.note("two");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "cvo-x: one\ncvo-x: two\n");
  EXPECT_EQ(notes.last(), "two");
}

}  // namespace
}  // namespace cvo::daemon
