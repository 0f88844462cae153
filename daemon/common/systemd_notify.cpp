#include "daemon/common/systemd_notify.hpp"

#include <cstdint>

#include <systemd/sd-daemon.h>

namespace cvo::daemon {

SystemdNotifier::SystemdNotifier() {
  std::uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0 && usec > 0)
    watchdog_period_ = std::chrono::microseconds(static_cast<std::int64_t>(usec / 2));
}

// sd_notify's result is ignored on purpose: a lost notification is systemd's to report, and the
// daemon must keep working without a service manager.
void SystemdNotifier::ready() const { sd_notify(0, "READY=1"); }
void SystemdNotifier::status(const std::string& text) const { sd_notify(0, ("STATUS=" + text).c_str()); }
void SystemdNotifier::stopping() const { sd_notify(0, "STOPPING=1"); }
void SystemdNotifier::watchdog() const { sd_notify(0, "WATCHDOG=1"); }

}  // namespace cvo::daemon
