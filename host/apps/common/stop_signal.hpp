// SIGINT/SIGTERM -> a clean stop of a daemon loop, shared by `omnilocd` and `omnilocd-sim`.
#pragma once

#include <csignal>

namespace omniloc::cli {

/// The flag the daemon loop polls. The one piece of global state: a signal handler can only reach
/// a static object, and the only thing it may safely do is set a volatile sig_atomic_t.
inline volatile std::sig_atomic_t g_stop_requested = 0;

extern "C" inline void on_stop_signal(int) {
  g_stop_requested = 1;
}

/// No SA_RESTART: a blocking read returns early and the loop sees the flag.
inline void install_stop_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

}  // namespace omniloc::cli
