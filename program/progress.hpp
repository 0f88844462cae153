#pragma once
// A one-line progress bar on stderr: frames done / total, rate, ETA. Drawn only when stderr is a
// terminal, so logs and scripts that capture stderr never see carriage returns.
#include <chrono>
#include <cstddef>

namespace cvo::program {

class ProgressBar {
 public:
  /// Enabled when `enabled` and stderr is a terminal (isatty).
  ProgressBar(std::size_t total, bool enabled = true);
  ~ProgressBar();  // clears the line
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// `done` frames finished; redraws at most every 100 ms, and always at the last frame.
  void update(std::size_t done);
  void finish();  // clears the line; idempotent

 private:
  using Clock = std::chrono::steady_clock;
  std::size_t total_;
  bool active_;
  Clock::time_point start_, last_draw_;
};

}  // namespace cvo::program
