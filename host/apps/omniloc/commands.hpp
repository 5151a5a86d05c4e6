// Subcommands of the `omniloc` command line; one file each, dispatched from main.cpp.
#pragma once

#include <span>
#include <string_view>

#include "command_table.hpp"

namespace omniloc::cli {

int cmd_version(std::span<const std::string_view> args);
int cmd_regmap(std::span<const std::string_view> args);
int cmd_probe(std::span<const std::string_view> args);
int cmd_builddb(std::span<const std::string_view> args);
int cmd_replay(std::span<const std::string_view> args);
int cmd_calibrate(std::span<const std::string_view> args);

}  // namespace omniloc::cli
