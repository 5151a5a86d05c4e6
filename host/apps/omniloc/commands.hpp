// Subcommands of the `omniloc` command line (CLI11, subcommand_cli.hpp); one file each, registered
// on the program's app by main.cpp.
#pragma once

#include "subcommand_cli.hpp"

namespace omniloc::cli {

Subcommand add_version(CLI::App& program);
Subcommand add_regmap(CLI::App& program);
Subcommand add_probe(CLI::App& program);
Subcommand add_builddb(CLI::App& program);
Subcommand add_replay(CLI::App& program);
Subcommand add_calibrate(CLI::App& program);
Subcommand add_locate(CLI::App& program);
Subcommand add_ctl(CLI::App& program);

}  // namespace omniloc::cli
