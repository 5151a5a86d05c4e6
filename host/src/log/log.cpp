#include "omniloc/log.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace omniloc {

namespace {
constexpr std::array<std::string_view, 4> kNames = {"error", "warning", "info", "debug"};
}

std::string_view to_string(LogLevel level) {
  return kNames.at(static_cast<std::size_t>(level));
}

LogLevel parse_log_level(std::string_view text, std::string_view what) {
  for (std::size_t i = 0; i < kNames.size(); ++i)
    if (text == kNames[i]) return static_cast<LogLevel>(i);
  throw std::invalid_argument(std::string(what) +
                              ": must be one of error, warning, info, debug (got '" +
                              std::string(text) + "')");
}

LogLevel adjust_log_level(LogLevel base, int verbose, int quiet) {
  const int level =
      std::clamp(static_cast<int>(base) + verbose - quiet, 0, static_cast<int>(kNames.size()) - 1);
  return static_cast<LogLevel>(level);
}

std::string format_log_line(std::string_view program, LogLevel level, std::string_view message) {
  std::string line(program);
  line += ": ";
  if (level != LogLevel::kInfo) {
    line += to_string(level);
    line += ": ";
  }
  line += message;
  return line;
}

Logger::Logger() : Logger(LogLevel::kInfo, stderr_sink("omniloc")) {}

Logger::Logger(LogLevel threshold, Sink sink) : threshold_(threshold), sink_(std::move(sink)) {
  if (!sink_) throw std::invalid_argument("Logger: a sink is required");
}

Logger::Sink Logger::stderr_sink(std::string program) {
  return [program = std::move(program)](LogLevel level, std::string_view message) {
    const std::string line = format_log_line(program, level, message) + "\n";
    std::fwrite(line.data(), 1, line.size(),
                stderr);  // one write per line: lines of threads do not mix
  };
}

Logger Logger::silent() {
  return Logger(LogLevel::kError, [](LogLevel, std::string_view) {});
}

void Logger::log(LogLevel level, std::string_view message) const {
  if (enabled(level)) sink_(level, message);
}

}  // namespace omniloc
