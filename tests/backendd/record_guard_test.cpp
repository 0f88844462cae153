// cvo-backendd's guard around each record and each step of its own (record_guard.hpp): whatever
// the step throws costs that step, counted as a refusal (the mapper's MapperError) or a failure
// (anything else, as the map::at of issue 48), and noted; nothing escapes.
#include "daemon/backendd/record_guard.hpp"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace cvo::daemon::backendd {
namespace {

TEST(RecordGuard, AStepThatThrowsMapAtIsACountedFailureAndNothingEscapes) {
  Notes notes("record_guard_test");
  RecordGuard guard(notes);
  const auto outcome = guard.run("record", [] { throw std::out_of_range("map::at"); });
  EXPECT_EQ(outcome, StepOutcome::kFailed);
  EXPECT_EQ(guard.failed(), 1);
  EXPECT_EQ(guard.refused(), 0);
  EXPECT_EQ(notes.last(), "record skipped after a failure: map::at");
}

TEST(RecordGuard, ARecordTheMapperRefusesIsACountedRefusalNotAFailure) {
  Notes notes("record_guard_test");
  RecordGuard guard(notes);
  EXPECT_EQ(guard.run("record", [] { throw slam::MapperError("keyframe 3 of session 1 is out of order"); }),
            StepOutcome::kRefused);
  EXPECT_EQ(guard.refused(), 1);
  EXPECT_EQ(guard.failed(), 0);
  EXPECT_EQ(notes.last(), "not applied: keyframe 3 of session 1 is out of order");
}

TEST(RecordGuard, EvenAnExceptionOfNoStandardTypeCostsOnlyItsStep) {
  Notes notes("record_guard_test");
  RecordGuard guard(notes);
  EXPECT_EQ(guard.run("settling", [] { throw 42; }), StepOutcome::kFailed);
  EXPECT_EQ(guard.failed(), 1);
  int ran = 0;
  EXPECT_EQ(guard.run("record", [&] { ++ran; }), StepOutcome::kDone) << "the next step runs";
  EXPECT_EQ(ran, 1);
  EXPECT_EQ(guard.failed(), 1);
}

}  // namespace
}  // namespace cvo::daemon::backendd
