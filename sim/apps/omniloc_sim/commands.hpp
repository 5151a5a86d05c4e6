// Subcommands of `omniloc-sim`, the simulator's command line (CLI11, subcommand_cli.hpp); one file
// each, registered on the program's app by main.cpp.
#pragma once

#include "subcommand_cli.hpp"

namespace omniloc::cli {

/// `bench paper` (`bench` holds the benchmarks; `paper` is the one there is).
Subcommand add_bench_paper(CLI::App& program);
Subcommand add_demo(CLI::App& program);
/// `venues`: sampled cameras, robots and venues with their truth (omniloc_sim/venue.hpp).
Subcommand add_venues(CLI::App& program);

}  // namespace omniloc::cli
