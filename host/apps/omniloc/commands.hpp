// Subcommands of the `omniloc` command line; one file each, dispatched from main.cpp.
#pragma once

#include <cmath>
#include <cstdlib>
#include <span>
#include <string>
#include <string_view>

#include "command_table.hpp"

namespace omniloc::cli {

int cmd_version(std::span<const std::string_view> args);
int cmd_regmap(std::span<const std::string_view> args);
int cmd_probe(std::span<const std::string_view> args);
int cmd_builddb(std::span<const std::string_view> args);
int cmd_replay(std::span<const std::string_view> args);
int cmd_calibrate(std::span<const std::string_view> args);
int cmd_locate(std::span<const std::string_view> args);
int cmd_ctl(std::span<const std::string_view> args);

/// A whole argument as a finite number ("12", "-3.5", "1e2"); false for "", "12x", "nan", "inf".
inline bool parse_number(std::string_view text, double& out) {
  const std::string s(text);
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(out);
}

}  // namespace omniloc::cli
