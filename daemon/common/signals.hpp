#pragma once
// SIGTERM and SIGINT as a stop request, without async handlers: the signals are blocked in every
// thread (call block_stop_signals() before starting any) and the main thread waits for them
// with a timeout, so shutdown runs as ordinary code that can flush and join.
#include <chrono>
#include <optional>

namespace cvo::daemon {

void block_stop_signals();

/// Waits up to `timeout` for SIGTERM or SIGINT; returns the signal number, or nullopt.
std::optional<int> wait_for_stop_signal(std::chrono::milliseconds timeout);

}  // namespace cvo::daemon
