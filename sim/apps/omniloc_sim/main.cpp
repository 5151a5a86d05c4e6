// `omniloc-sim`: what runs on the simulated robot only (the robot's tools are in `omniloc`, the
// simulated robot daemon is `omnilocd-sim`).
#include "command_table.hpp"
#include "commands.hpp"

namespace {

constexpr omniloc::cli::CommandEntry kCommands[] = {
    {"demo", "the robot's daemon on the simulated robot: 30 s drive, error table, paths.png", omniloc::cli::cmd_demo},
    {"bench", "`bench paper`: the paper's Tables 1-8 reproduced in simulation", omniloc::cli::cmd_bench},
};

}  // namespace

int main(int argc, char** argv) { return omniloc::cli::run_command_table(argc, argv, "omniloc-sim", kCommands); }
