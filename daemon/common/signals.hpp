#pragma once
// SIGTERM, SIGINT and SIGHUP as a stop request, without async handlers: the signals are blocked
// in every thread and the main thread waits for them with a timeout, so shutdown runs as ordinary
// code that can flush and join. SIGHUP stops cleanly too (a daemon's configuration is read once:
// restart it to apply a new one), where its default action would kill the process mid-work.
//
// Each daemon links stop_signals_at_start (early_signals.cpp): the signals are blocked before any
// library initialiser runs, so a stop that comes in the first instant waits, pending, until the
// daemon can stop cleanly.
#include <chrono>
#include <optional>

namespace cvo::daemon {

void block_stop_signals();

/// Waits up to `timeout` for a stop signal; returns the signal number, or nullopt.
std::optional<int> wait_for_stop_signal(std::chrono::milliseconds timeout);

/// "SIGTERM", "SIGINT", "SIGHUP".
const char* signal_name(int signal);

}  // namespace cvo::daemon
