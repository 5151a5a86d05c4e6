// The subcommand dispatcher shared by `omniloc` (host/apps/omniloc) and `omniloc-sim`
// (sim/apps/omniloc_sim): a table of commands, usage from it, exit codes 0 / 1 / 2.
#pragma once

#include <cstdio>
#include <exception>
#include <span>
#include <string_view>
#include <vector>

#include "omniloc/version.hpp"

namespace omniloc::cli {

/// Every subcommand takes its own arguments (argv after the subcommand name) and returns the
/// process exit code: 0 success, 1 failure, 2 bad usage.
using Command = int (*)(std::span<const std::string_view> args);

struct CommandEntry {
  std::string_view name;
  std::string_view summary;
  Command run;
};

inline void print_command_usage(std::FILE* out, std::string_view program, std::span<const CommandEntry> commands) {
  std::fprintf(out, "usage: %.*s COMMAND [ARGS...]\n\ncommands:\n", static_cast<int>(program.size()), program.data());
  for (const auto& c : commands)
    std::fprintf(out, "  %-10.*s %.*s\n", static_cast<int>(c.name.size()), c.name.data(),
                 static_cast<int>(c.summary.size()), c.summary.data());
  std::fprintf(out, "\n`%.*s COMMAND --help` describes one command; `%.*s --version` says what this is.\n",
               static_cast<int>(program.size()), program.data(), static_cast<int>(program.size()), program.data());
}

/// Runs the command argv[1] names with argv[2...]; an exception becomes "PROGRAM CMD: error: ..." and 1.
inline int run_command_table(int argc, char** argv, std::string_view program, std::span<const CommandEntry> commands) {
  if (argc < 2) {
    print_command_usage(stderr, program, commands);
    return 2;
  }
  const std::string_view name = argv[1];
  if (name == "-h" || name == "--help" || name == "help") {
    print_command_usage(stdout, program, commands);
    return 0;
  }
  if (name == "--version") {
    std::printf("%s\n", version_line(program).c_str());
    return 0;
  }
  const std::vector<std::string_view> args(argv + 2, argv + argc);
  for (const auto& c : commands) {
    if (c.name != name) continue;
    try {
      return c.run(args);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%.*s %s: error: %s\n", static_cast<int>(program.size()), program.data(), argv[1], e.what());
      return 1;
    }
  }
  std::fprintf(stderr, "%.*s: unknown command '%s'\n\n", static_cast<int>(program.size()), program.data(), argv[1]);
  print_command_usage(stderr, program, commands);
  return 2;
}

}  // namespace omniloc::cli
