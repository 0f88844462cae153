#include "daemon/common/supervise.hpp"

#include <algorithm>

#include "daemon/common/signals.hpp"

namespace cvo::daemon {

std::optional<int> supervise(const SystemdNotifier& systemd, const Workers& workers,
                             const std::function<bool()>& ended) {
  using namespace std::chrono_literals;
  using Clock = std::chrono::steady_clock;
  auto last_watchdog = Clock::now();
  std::optional<int> signal;
  while (!(signal = wait_for_stop_signal(50ms)) && !ended()) {
    const auto period = systemd.watchdog_period();
    if (!period || Clock::now() - last_watchdog < *period) continue;
    const auto alive = [&](const Heartbeat* h) { return h->fresh(workers.max_silence); };
    if (std::all_of(workers.heartbeats.begin(), workers.heartbeats.end(), alive)) systemd.watchdog();
    last_watchdog = Clock::now();
  }
  systemd.stopping();
  return signal;
}

}  // namespace cvo::daemon
