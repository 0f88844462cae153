#pragma once
// How many times slower this build runs than Release: 1, or more under a sanitizer (ASan about 4,
// TSan about 10; tests/CMakeLists.txt sets it from CVO_SANITIZE). Tests that pace real processes
// (a recording played at a rate, a deadline for shutdown) scale their rates and waits by it, so
// that a sanitizer build checks the same behaviour instead of failing on time.
#include <chrono>

#ifndef CVO_TEST_SLOWDOWN
#define CVO_TEST_SLOWDOWN 1
#endif

namespace cvo::testing {

inline constexpr double kSlowdown = CVO_TEST_SLOWDOWN;

/// `d` stretched by kSlowdown.
template <class Rep, class Period>
std::chrono::milliseconds scaled(std::chrono::duration<Rep, Period> d) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(d * kSlowdown);
}

}  // namespace cvo::testing
