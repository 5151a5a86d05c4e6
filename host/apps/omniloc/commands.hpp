// Subcommands of the `omniloc` command line; one file each, dispatched from main.cpp.
#pragma once

#include <span>
#include <string_view>

namespace omniloc::cli {

/// Every subcommand takes its own arguments (argv after the subcommand name) and returns the
/// process exit code: 0 success, 1 failure, 2 bad usage.
using Command = int (*)(std::span<const std::string_view> args);

int cmd_version(std::span<const std::string_view> args);
int cmd_regmap(std::span<const std::string_view> args);
int cmd_probe(std::span<const std::string_view> args);
int cmd_builddb(std::span<const std::string_view> args);
int cmd_replay(std::span<const std::string_view> args);
int cmd_bench(std::span<const std::string_view> args);
int cmd_demo(std::span<const std::string_view> args);

}  // namespace omniloc::cli
