// `omniloc`: the command line of the omniloc host library (the robot's tools; the simulator's
// `demo` and `bench paper` are in `omniloc-sim`, sim/apps/omniloc_sim).
#include "commands.hpp"

int main(int argc, char** argv) {
  namespace cli = omniloc::cli;
  CLI::App app{"omniloc: the robot's tools (docs/HOWTO.md)."};
  cli::setup_program(app, "omniloc");
  std::vector<cli::Subcommand> commands = {
      cli::add_version(app), cli::add_regmap(app), cli::add_probe(app), cli::add_builddb(app),
      cli::add_replay(app),  cli::add_locate(app), cli::add_ctl(app)};
#ifdef OMNILOC_WITH_CALIBRATION
  commands.push_back(cli::add_calibrate(app));
#endif
  return cli::run_program(app, argc, argv, commands);
}
