#pragma once
// The main thread of both daemons, once their workers run: it waits for a stop signal or for the
// daemon's own end, and serves systemd's watchdog meanwhile, but only while every worker's
// heartbeat is fresh (a hung worker stops the pings, and systemd restarts the daemon).
#include <chrono>
#include <functional>
#include <optional>
#include <span>

#include "daemon/common/heartbeat.hpp"
#include "daemon/common/systemd_notify.hpp"

namespace cvo::daemon {

struct Workers {
  std::span<const Heartbeat* const> heartbeats;
  std::chrono::nanoseconds max_silence;  // the longest a worker may go without a beat
};

/// Returns the stop signal that came (SIGTERM, SIGINT or SIGHUP: signals.hpp), or nullopt once
/// `ended()` is true. READY is the caller's; STOPPING is sent here, whichever way it ends.
std::optional<int> supervise(const SystemdNotifier& systemd, const Workers& workers,
                             const std::function<bool()>& ended);

}  // namespace cvo::daemon
