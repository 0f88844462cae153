#pragma once
// Heap allocations counted per thread, so a daemon can prove its realtime thread does not
// allocate after warm-up (CVO_STATUS.allocations_after_warmup). Linking allocation_counter.cpp
// into an executable replaces the global operator new; the count is a thread_local increment,
// cheap enough to leave on in production.
#include <cstdint>

namespace cvo::daemon {

/// Allocations made by the calling thread since it started.
std::int64_t thread_allocations();

}  // namespace cvo::daemon
