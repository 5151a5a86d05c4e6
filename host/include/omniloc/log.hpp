// One logging facility for every omniloc program and the daemon library: a Logger value holds a
// threshold and a sink; messages below the threshold cost one comparison. No global logger: the
// program makes one from its command line (--log-level, -v, -q) and hands it to what logs.
//   error    something failed (the program or the recording stops)
//   warning  something is wrong but the work goes on (control channel off, board lost)
//   info     what a person running it wants to see (status lines, progress, board open)
//   debug    detail for finding a fault (each refused frame, each control request)
#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace omniloc {

enum class LogLevel { kError = 0, kWarning = 1, kInfo = 2, kDebug = 3 };

/// "error", "warning", "info", "debug".
[[nodiscard]] std::string_view to_string(LogLevel level);

/// The level a user typed (one of the four names); throws std::invalid_argument naming `what` and
/// the text and listing the names.
[[nodiscard]] LogLevel parse_log_level(std::string_view text, std::string_view what);

/// The level after `verbose` -v and `quiet` -q flags applied to `base` (each one step, clamped).
[[nodiscard]] LogLevel adjust_log_level(LogLevel base, int verbose, int quiet);

class Logger {
 public:
  using Sink = std::function<void(LogLevel, std::string_view)>;

  /// Info and above to standard error, prefixed "omniloc: ".
  Logger();
  Logger(LogLevel threshold, Sink sink);

  /// Writes "PROGRAM: MESSAGE" for info, "PROGRAM: warning: MESSAGE" (error:, debug:) otherwise, a
  /// line each, to standard error.
  [[nodiscard]] static Sink stderr_sink(std::string program);
  /// A logger that drops everything (tests that do not look at the log).
  [[nodiscard]] static Logger silent();

  [[nodiscard]] LogLevel threshold() const { return threshold_; }
  [[nodiscard]] bool enabled(LogLevel level) const {
    return static_cast<int>(level) <= static_cast<int>(threshold_);
  }

  void log(LogLevel level, std::string_view message) const;
  void error(std::string_view message) const { log(LogLevel::kError, message); }
  void warning(std::string_view message) const { log(LogLevel::kWarning, message); }
  void info(std::string_view message) const { log(LogLevel::kInfo, message); }
  void debug(std::string_view message) const { log(LogLevel::kDebug, message); }

 private:
  LogLevel threshold_;
  Sink sink_;
};

/// "PROGRAM: warning: MESSAGE" (no level tag for info): the line the stderr sink writes.
[[nodiscard]] std::string format_log_line(std::string_view program, LogLevel level,
                                          std::string_view message);

}  // namespace omniloc
