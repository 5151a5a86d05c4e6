// `omniloc-sim`: what runs on the simulated robot only (the robot's tools are in `omniloc`, the
// simulated robot daemon is `omnilocd-sim`).
#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"omniloc-sim: the simulated robot's programs (docs/DAEMON.md, docs/LOCALIZER.md)."};
  omniloc::cli::setup_program(app, "omniloc-sim");
  const std::vector<omniloc::cli::Subcommand> commands = {omniloc::cli::add_demo(app),
                                                          omniloc::cli::add_bench_paper(app),
                                                          omniloc::cli::add_venues(app)};
  return omniloc::cli::run_program(app, argc, argv, commands);
}
