// The daemon as a systemd service (Type=notify, packaging/systemd/omnilocd.service): READY=1 once
// it runs, WATCHDOG=1 from its main loop at half the unit's WatchdogSec (so a hung loop is
// restarted, while a robot with no board keeps its daemon), STATUS= the latest status line,
// STOPPING=1 at the end. Through libsystemd's sd_notify; outside systemd (no NOTIFY_SOCKET) every
// call does nothing.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace omniloc {

class ServiceNotifier {
 public:
  /// Reads the watchdog interval the service manager set (WATCHDOG_USEC, for this process).
  ServiceNotifier();
  void ready();
  /// Called every loop turn: sends WATCHDOG=1 when half the interval has passed since the last one.
  void loop(double now_ms);
  void status(const std::string& line);
  void stopping();

 private:
  std::uint64_t watchdog_us_ = 0;  ///< 0: the service manager asked for no watchdog
  std::optional<double> last_ping_ms_;
};

}  // namespace omniloc
