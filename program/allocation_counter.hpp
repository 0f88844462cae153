#pragma once
// Heap allocations counted, so that a daemon can prove its realtime thread does not allocate after
// warm-up (CVO_STATUS.allocations_after_warmup) and a test can prove the same of the code it calls.
// Linking allocation_counter.cpp into an executable (the cvo_allocation_counter object library)
// replaces every form of the global operator new/delete; a thread_local increment and a relaxed
// atomic one are cheap enough to leave on in production.
#include <cstdint>

namespace cvo::program {

/// Allocations made by the calling thread since it started.
std::int64_t thread_allocations();

/// Allocations made by every thread of the process (worker threads such as OpenMP's included).
std::int64_t process_allocations();

}  // namespace cvo::program
