// `omniloc`: the command line of the omniloc host library.
#include <cstdio>
#include <exception>
#include <string_view>
#include <vector>

#include "commands.hpp"

namespace {

struct Entry {
  std::string_view name;
  std::string_view summary;
  omniloc::cli::Command run;
};

constexpr Entry kCommands[] = {
    {"version", "print the host version and the register-map version it speaks", omniloc::cli::cmd_version},
    {"regmap", "print the register map the host was built against", omniloc::cli::cmd_regmap},
    {"probe", "find omniloc boards on USB, print ID/version/status and live counts", omniloc::cli::cmd_probe},
    {"builddb", "build the vision feature database (field x camera x grid) with progress", omniloc::cli::cmd_builddb},
    {"replay", "run the localizer over a recording directory, write poses.csv, errors vs truth", omniloc::cli::cmd_replay},
    {"bench", "`bench paper`: the paper's Tables 1-8 reproduced in simulation", omniloc::cli::cmd_bench},
    {"demo", "the whole system on the simulated robot: 30 s drive, error table, paths.png", omniloc::cli::cmd_demo},
};

void usage(std::FILE* out) {
  std::fprintf(out, "usage: omniloc COMMAND [ARGS...]\n\ncommands:\n");
  for (const auto& c : kCommands) {
    std::fprintf(out, "  %-10.*s %.*s\n", static_cast<int>(c.name.size()), c.name.data(),
                 static_cast<int>(c.summary.size()), c.summary.data());
  }
  std::fprintf(out, "\n`omniloc COMMAND --help` describes one command.\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const std::string_view name = argv[1];
  if (name == "-h" || name == "--help" || name == "help") {
    usage(stdout);
    return 0;
  }
  std::vector<std::string_view> args(argv + 2, argv + argc);
  for (const auto& c : kCommands) {
    if (c.name == name) {
      try {
        return c.run(args);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "omniloc %s: error: %s\n", argv[1], e.what());
        return 1;
      }
    }
  }
  std::fprintf(stderr, "omniloc: unknown command '%s'\n\n", argv[1]);
  usage(stderr);
  return 2;
}
