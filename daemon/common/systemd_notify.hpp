#pragma once
// The daemon's side of systemd's Type=notify protocol (sd_notify(3)), through libsystemd:
// READY=1 once serving, STATUS=... for `systemctl status`, WATCHDOG=1 at half the WatchdogSec
// interval, STOPPING=1 on the way out. Outside systemd (no NOTIFY_SOCKET) every call is a no-op.
#include <chrono>
#include <optional>
#include <string>

namespace cvo::daemon {

class SystemdNotifier {
 public:
  SystemdNotifier();  // reads WATCHDOG_USEC (sd_watchdog_enabled) once

  void ready() const;
  void status(const std::string& text) const;
  void stopping() const;
  void watchdog() const;

  /// How often watchdog() must be called (half systemd's interval); nullopt without a watchdog.
  [[nodiscard]] std::optional<std::chrono::microseconds> watchdog_period() const { return watchdog_period_; }

 private:
  std::optional<std::chrono::microseconds> watchdog_period_;
};

}  // namespace cvo::daemon
