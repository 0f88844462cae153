#pragma once
// A worker thread's sign of life: it beats once per loop turn, and the supervisor serves systemd's
// watchdog only while every worker beat recently, so that a hung thread gets the daemon restarted.
// One atomic word: any thread may beat, the realtime one included.
#include <atomic>
#include <chrono>
#include <cstdint>

#include "libcvo/core/units.hpp"

namespace cvo::daemon {

class Heartbeat {
 public:
  Heartbeat() { beat(); }
  void beat() { ns_.store(core::steady_now_ns(), std::memory_order_relaxed); }
  /// Whether the last beat is at most `max_silence` ago.
  [[nodiscard]] bool fresh(std::chrono::nanoseconds max_silence) const {
    return core::steady_now_ns() - ns_.load(std::memory_order_relaxed) <= max_silence.count();
  }

 private:
  std::atomic<std::int64_t> ns_{0};
};

}  // namespace cvo::daemon
