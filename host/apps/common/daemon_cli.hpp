// The command line of omnilocd and omnilocd-sim, with CLI11: `--config FILE`, then one option per
// key of the daemon's key table (daemon_config_keys(): the same table drives the JSON reader), as
// `--udp-port 5600` or `--udp-port=5600`, plus --help (every option, its default) and --version.
// The values are parsed by the key table (set_daemon_key), so a flag and a config file refuse the
// same things with the same messages; flags override the file whatever their order.
#pragma once

#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "omniloc/daemon_config.hpp"
#include "omniloc/detail/config_reader.hpp"
#include "omniloc/log.hpp"

namespace omniloc::cli {

struct DaemonCommandLine {
  std::string config_path;
  std::vector<std::string> keys;                   ///< daemon_config_keys() order
  std::vector<std::optional<std::string>> values;  ///< the text given for each key, if any
  int verbose = 0;                                 ///< -v given this many times
  int quiet = 0;                                   ///< -q given this many times
};

/// "udp_port" -> "udp-port".
inline std::string flag_of(std::string_view key) {
  std::string flag(key);
  for (char& ch : flag)
    if (ch == '_') ch = '-';
  return flag;
}

/// Short forms of some keys' flags: `--http 8080` for `--http-port 8080` (the live view).
inline std::string flag_names_of(std::string_view key) {
  const std::string names = "--" + flag_of(key);
  return key == "http_port" ? "--http," + names : names;
}

/// Adds --config and one option per daemon key to `app`; the values land in `cl` (which must
/// outlive the parse).
inline void add_daemon_options(CLI::App& app, DaemonCommandLine& cl) {
  app.add_option("--config", cl.config_path,
                 "JSON config file (docs/DAEMON.md); the flags below override it");
  const auto& table = daemon::daemon_config_keys();
  cl.keys.clear();
  cl.values.assign(table.size(), std::nullopt);  // sized once: the callbacks keep pointers into it
  const daemon::DaemonConfig defaults;
  for (std::size_t i = 0; i < table.size(); ++i) {
    const auto& k = table[i];
    cl.keys.emplace_back(k.name);
    const config::Json v = *k.write(defaults);
    const std::string shown = v.is_string() ? "\"" + v.get<std::string>() + "\"" : v.dump();
    std::optional<std::string>* slot = &cl.values[i];
    if (k.kind == config::Kind::kBoolean) {
      // A switch is a flag (--record-overwrite), with --no-... to undo a config file's true.
      const std::string name = flag_of(k.name);
      app.add_flag_function(
          "--" + name + ",!--no-" + name,
          [slot](std::int64_t count) { *slot = count > 0 ? "true" : "false"; },
          std::string(k.help) + " (default " + shown + ")");
      continue;
    }
    app.add_option_function<std::string>(
           flag_names_of(k.name), [slot](const std::string& text) { *slot = text; },
           std::string(k.help))
        ->type_name(k.kind == config::Kind::kText ? "TEXT" : "NUMBER")
        ->default_str(shown);
  }
  app.add_flag("-v,--verbose", cl.verbose, "log one level more than log_level (repeatable: -vv)");
  app.add_flag("-q,--quiet", cl.quiet,
               "log one level less than log_level (repeatable: -qq: errors only)");
}

/// The program's logger: the config's log_level moved by -v / -q, to standard error as "PROGRAM:
/// ...".
inline Logger daemon_logger(const daemon::DaemonConfig& config, const DaemonCommandLine& cl,
                            std::string program) {
  const LogLevel base = parse_log_level(config.log_level, "log_level");
  return Logger(adjust_log_level(base, cl.verbose, cl.quiet),
                Logger::stderr_sink(std::move(program)));
}

/// The configuration the command line asks for: the defaults, the --config file over them, each
/// given flag over that; validated. Throws ConfigError naming the file or "command line" and the
/// key.
inline daemon::DaemonConfig daemon_config_from(const DaemonCommandLine& cl) {
  daemon::DaemonConfig c;
  if (!cl.config_path.empty()) c = daemon::load_daemon_config(cl.config_path);
  for (std::size_t i = 0; i < cl.keys.size(); ++i)
    if (cl.values[i]) daemon::set_daemon_key(c, cl.keys[i], *cl.values[i], "command line");
  c.validate(cl.config_path.empty() ? "command line" : cl.config_path + " + command line");
  return c;
}

/// CLI11's answer to a parse: 0 after --help / --version (printed to stdout), else the message on
/// stderr and 2 (bad usage, as for a bad value).
inline int exit_code_of(const CLI::App& app, const CLI::ParseError& e) {
  const int rc = app.exit(e);
  return rc == 0 ? 0 : 2;
}

/// Parses the command line into `app`'s options, then calls run() (which returns the exit code):
/// 0 / 2 from the parse (help, version, bad usage), 2 for a ConfigError (a bad value or file), 1
/// for any other failure, each with "PROGRAM: error: ..." on stderr.
template <class Run>
int parse_and_run(CLI::App& app, int argc, char** argv, const char* program, Run run) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return exit_code_of(app, e);
  }
  try {
    return run();
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 1;
  }
}

}  // namespace omniloc::cli
