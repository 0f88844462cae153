#include "daemon/backendd/record_guard.hpp"

namespace cvo::daemon::backendd {

// Counted before it is noted: a note that cannot be made (out of memory) must not lose the count.
StepOutcome RecordGuard::refuse(const char* why) noexcept {
  ++refused_;
  try {
    notes_.note_limited("not applied", std::string("not applied: ") + why);
  } catch (...) {  // nothing more can be said
  }
  return StepOutcome::kRefused;
}

StepOutcome RecordGuard::fail(std::string_view what, const char* why) noexcept {
  ++failed_;
  try {
    notes_.note_limited("failure", std::string(what) + " skipped after a failure: " + why);
  } catch (...) {  // nothing more can be said
  }
  return StepOutcome::kFailed;
}

}  // namespace cvo::daemon::backendd
