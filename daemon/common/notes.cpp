#include "daemon/common/notes.hpp"

#include <iostream>
#include <utility>

namespace cvo::daemon {

void Notes::note(const std::string& detail) {
  const std::lock_guard lock(mutex_);
  std::cerr << process_ << ": " << detail << std::endl;  // under the lock: whole lines, in order
  last_ = detail;
}

void Notes::note_limited(const std::string& kind, const std::string& detail) {
  long long held_back = 0;
  {
    const std::lock_guard lock(mutex_);
    auto& limit = limits_[kind];
    const auto now = std::chrono::steady_clock::now();
    if (limit.last != std::chrono::steady_clock::time_point{} && now - limit.last < period) {
      ++limit.held_back;
      return;
    }
    held_back = std::exchange(limit.held_back, 0);
    limit.last = now;
  }
  note(held_back == 0 ? detail : detail + " (and " + std::to_string(held_back) + " like it not shown)");
}

std::string Notes::last() const {
  const std::lock_guard lock(mutex_);
  return last_;
}

}  // namespace cvo::daemon
