// Subcommands of `omniloc-sim`, the simulator's command line; one file each, dispatched from main.cpp.
#pragma once

#include <span>
#include <string_view>

#include "command_table.hpp"

namespace omniloc::cli {

int cmd_bench(std::span<const std::string_view> args);
int cmd_demo(std::span<const std::string_view> args);

}  // namespace omniloc::cli
