// Linked into each daemon's executable as an object (stop_signals_at_start): the stop signals are
// blocked from .preinit_array, which the dynamic loader runs before any shared library's
// initialiser and long before main(), so that a SIGTERM in the first instant is a clean stop
// (signals.hpp), not a kill of a half-started process. Threads inherit the mask.
#include "daemon/common/signals.hpp"

namespace {

void block_at_start(int /*argc*/, char** /*argv*/, char** /*envp*/) { cvo::daemon::block_stop_signals(); }

[[gnu::used, gnu::section(".preinit_array")]] void (*block_stop_signals_at_start)(int, char**, char**) = block_at_start;

}  // namespace
