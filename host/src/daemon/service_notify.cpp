#include "omniloc/detail/service_notify.hpp"

#include <systemd/sd-daemon.h>

namespace omniloc {

ServiceNotifier::ServiceNotifier() {
  std::uint64_t us = 0;
  // > 0 only when WATCHDOG_USEC is set (and WATCHDOG_PID, if set, is this process).
  if (sd_watchdog_enabled(0, &us) > 0) watchdog_us_ = us;
}

void ServiceNotifier::ready() {
  sd_notify(0, "READY=1");
}

void ServiceNotifier::loop(double now_ms) {
  if (watchdog_us_ == 0) return;
  if (last_ping_ms_ && now_ms - *last_ping_ms_ < static_cast<double>(watchdog_us_) / 2000.0) return;
  last_ping_ms_ = now_ms;
  sd_notify(0, "WATCHDOG=1");
}

void ServiceNotifier::status(const std::string& line) {
  sd_notifyf(0, "STATUS=%s", line.c_str());
}

void ServiceNotifier::stopping() {
  sd_notify(0, "STOPPING=1");
}

}  // namespace omniloc
