// The command lines of `omniloc` (host/apps/omniloc) and `omniloc-sim` (sim/apps/omniloc_sim), with
// CLI11 as omnilocd's (daemon_cli.hpp): one CLI11 subcommand per command, `--key value` and
// `--key=value`, --help at the top and per command (every option, its default), --version.
// Every number goes through the one strict parser (omniloc/detail/strict_number.hpp) in the
// option's callback, so "abc", "-1" for a count, "1.7" or "1e30" for an integer, "inf" are refused
// naming the flag and the text. Exit codes: 0 success (and --help, --version), 1 failure, 2 bad
// usage.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "omniloc/detail/strict_number.hpp"
#include "omniloc/version.hpp"

namespace omniloc::cli {

/// The strict parse of `text` as a T in [min, max]; `flag` names the option in the message.
template <class T>
T parse_number_as(const std::string& text, const std::string& flag, T min, T max) {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(
        parse_double(text, flag, static_cast<double>(min), static_cast<double>(max)));
  } else if constexpr (std::is_signed_v<T>) {
    return static_cast<T>(parse_int(text, flag, min, max));
  } else {
    return static_cast<T>(parse_uint(text, flag, min, max));
  }
}

/// "INT in [1, 65535]", "NUMBER in [1, 120]": the option's type and range in --help.
template <class T>
std::string number_type_name(T min, T max) {
  std::ostringstream os;
  os << (std::is_floating_point_v<T> ? "NUMBER" : std::is_signed_v<T> ? "INT" : "UINT");
  const bool whole_range =
      min == std::numeric_limits<T>::lowest() && max == std::numeric_limits<T>::max();
  if (!whole_range) os << " in [" << min << ", " << max << "]";
  return os.str();
}

template <class T>
std::string number_text(T value) {
  std::ostringstream os;
  os << value;
  return os.str();
}

/// A numeric option `flag` ("--seed") whose value, parsed strictly in [min, max], goes to
/// `store`; a bad text is a CLI11 ValidationError (exit 2) saying
/// "--seed: must be an integer in [0, ...] (got 'abc')".
template <class T>
CLI::Option* add_number_callback(CLI::App& app, const std::string& flag,
                                 std::function<void(T)> store, const std::string& help, T min,
                                 T max) {
  auto parse = [store = std::move(store), flag, min, max](const std::string& text) {
    try {
      store(parse_number_as<T>(text, flag, min, max));
    } catch (const NumberError& e) {
      throw CLI::ValidationError(e.what());
    }
  };
  return app.add_option_function<std::string>(flag, parse, help)
      ->type_name(number_type_name(min, max));
}

/// add_number_callback into `value`, whose value now is the default --help shows.
template <class T>
CLI::Option* add_number_option(CLI::App& app, const std::string& flag, T& value,
                               const std::string& help, T min = std::numeric_limits<T>::lowest(),
                               T max = std::numeric_limits<T>::max()) {
  return add_number_callback<T>(
             app, flag, [&value](T v) { value = v; }, help, min, max)
      ->default_str(number_text(value));
}

/// One subcommand: its CLI11 app (owned by the parent) and what runs when it was chosen. The
/// options it parses into live in the closure.
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// "omniloc-sim bench paper": the program and the subcommands chosen so far.
inline std::string command_path(const CLI::App& app) {
  std::string path = app.get_name();
  const CLI::App* at = &app;
  for (auto subs = at->get_subcommands(); !subs.empty(); subs = at->get_subcommands()) {
    at = subs.front();
    path += " " + at->get_name();
  }
  return path;
}

/// CLI11's failure message as "PROGRAM COMMAND: error: WHAT" and where to find the options.
inline std::string failure_message_with_path(const CLI::App* app, const CLI::Error& e) {
  const std::string path = command_path(*app);
  return path + ": error: " + e.what() + "\nRun '" + path +
         " --help' for every option and its default.\n";
}

/// The top-level app of a program with subcommands (call it before adding them): --version as
/// version_line(name), one command required, a flag takes no value, a failure printed by
/// failure_message_with_path.
inline void setup_program(CLI::App& app, const std::string& name) {
  app.name(name);
  app.set_version_flag("--version", version_line(name));
  app.require_subcommand(1);
  app.option_defaults()
      ->disable_flag_override();  // "--paper=3" is an error, not a flag set 3 times
  app.failure_message(failure_message_with_path);
}

/// Parses the command line and runs the chosen subcommand: 0 / 2 from the parse (help, version,
/// bad usage), else the command's exit code; an exception from it is "PROGRAM COMMAND: error: ..."
/// on stderr and 1. `help` as the first word is --help.
inline int run_program(CLI::App& app, int argc, char** argv,
                       const std::vector<Subcommand>& commands) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (!args.empty() && args.front() == "help") args.front() = "--help";
  const auto named = [&](const CLI::App* s) { return s->check_name(args.front()); };
  if (!args.empty() && !args.front().starts_with("-") &&
      std::as_const(app).get_subcommands(named).empty()) {
    std::fprintf(stderr, "%s: error: unknown command '%s'\n\n%s", app.get_name().c_str(),
                 args.front().c_str(), app.help().c_str());
    return 2;
  }
  std::reverse(args.begin(), args.end());  // CLI11's vector form takes the arguments last first
  try {
    app.parse(args);
  } catch (const CLI::RequiredError& e) {
    // CLI11 checks what is required before what is unknown: name the unknown option first.
    const std::vector<std::string> extra = app.remaining(true);
    return app.exit(extra.empty() ? CLI::ParseError(e) : CLI::ExtrasError(extra)) == 0 ? 0 : 2;
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  for (const auto& c : commands) {
    if (!c.app->parsed()) continue;
    try {
      return c.run();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: error: %s\n", command_path(app).c_str(), e.what());
      return 1;
    }
  }
  std::fprintf(stderr, "%s: no command chosen\n", app.get_name().c_str());
  return 2;
}

}  // namespace omniloc::cli
