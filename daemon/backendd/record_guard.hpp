#pragma once
// What one record, or one step of the back end's own (settling, the store's map after its replay,
// the final optimisation, the closing notes), may cost when it throws: that record or step, never
// the cvo-backend thread (an exception escaping it would end the process by std::terminate: the
// SIGABRT of issue 48) and never the map. Two kinds, counted apart for CVO_STATUS:
//   refused  slam::MapperError: the record cannot be applied (the mapper promises that nothing
//            changed); the input's fault. cvo-backendd adds them to bad_messages[BAD_CONTENT].
//   failed   anything else (std::out_of_range from a map lookup, std::bad_alloc, a broken invariant
//            of a debug build): the back end's own fault. cvo-backendd reports them as
//            failed_frames, which is a tracker's count otherwise.
// Each is noted at the one log-rate policy (daemon/common/notes.hpp).
#include <atomic>
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>

#include "daemon/common/notes.hpp"
#include "libcvo/slam/mapper.hpp"  // MapperError

namespace cvo::daemon::backendd {

enum class StepOutcome { kDone, kRefused, kFailed };

class RecordGuard {
 public:
  explicit RecordGuard(Notes& notes) : notes_(notes) {}

  /// Runs `step` (`what` names it in the notes: "record", "settling", ...); never throws.
  template <class Step>
  StepOutcome run(std::string_view what, Step&& step) noexcept {
    try {
      step();
      return StepOutcome::kDone;
    } catch (const slam::MapperError& e) {
      return refuse(e.what());
    } catch (const std::exception& e) {
      return fail(what, e.what());
    } catch (...) {
      return fail(what, "an exception of no standard type");
    }
  }

  [[nodiscard]] std::int64_t refused() const { return refused_; }
  [[nodiscard]] std::int64_t failed() const { return failed_; }

 private:
  StepOutcome refuse(const char* why) noexcept;
  StepOutcome fail(std::string_view what, const char* why) noexcept;

  Notes& notes_;
  // Read by CVO_STATUS, which cvo-backend publishes itself: atomic only so that any thread may read.
  std::atomic<std::int64_t> refused_{0}, failed_{0};
};

}  // namespace cvo::daemon::backendd
