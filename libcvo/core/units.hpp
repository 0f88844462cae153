#pragma once
// Angle units and elapsed time: the conversions every module needs, written once.
#include <chrono>
#include <cstdint>
#include <numbers>

namespace cvo::core {

/// Degrees to radians.
constexpr double radians(double degrees) { return degrees * std::numbers::pi / 180.0; }

/// Radians to degrees.
constexpr double degrees(double radians) { return radians * 180.0 / std::numbers::pi; }

using SteadyClock = std::chrono::steady_clock;

/// Milliseconds elapsed on the steady clock since `start`.
inline double ms_since(SteadyClock::time_point start) {
  return std::chrono::duration<double, std::milli>(SteadyClock::now() - start).count();
}

/// The steady clock in nanoseconds: a plain integer that fits in a std::atomic (heartbeats).
inline std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(SteadyClock::now().time_since_epoch()).count();
}

/// The wall clock in microseconds since the epoch: LCM's utime.
inline std::int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace cvo::core
