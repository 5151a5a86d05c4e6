// Harness: omnilocd's command line (host/apps/common/daemon_cli.hpp: CLI11 options from the
// daemon's key table, each value parsed by set_daemon_key as a config file's would be, then
// validated). Input: the arguments after the program name, one per line ('\n'). --config is
// dropped before the file is read (the JSON readers have a harness of their own). Expected errors:
// CLI11's ParseError (including --help and --version) and ConfigError naming "command line" and the
// key. A configuration that passes must validate again and survive being written and read back.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "daemon_cli.hpp"
#include "fuzz_common.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/detail/config_reader.hpp"

namespace {

using omniloc::fuzz::fuzz_check;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4096) return 0;  // a command line, not a file
  std::vector<std::string> args{"omnilocd"};
  std::string current;
  for (std::size_t i = 0; i < size; ++i) {
    const char ch = static_cast<char>(data[i]);
    if (ch == '\n') {
      args.push_back(current);
      current.clear();
    } else if (ch != '\0') {  // argv strings cannot hold a NUL
      current.push_back(ch);
    }
  }
  if (!current.empty()) args.push_back(current);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  CLI::App app{"omnilocd (fuzz)"};
  omniloc::cli::DaemonCommandLine cl;
  omniloc::cli::add_daemon_options(app, cl);
  try {
    app.parse(static_cast<int>(args.size()), argv.data());
  } catch (const CLI::ParseError&) {
    return 0;
  }
  cl.config_path.clear();
  try {
    const omniloc::daemon::DaemonConfig c = omniloc::cli::daemon_config_from(cl);
    c.validate("fuzz");
    // Each key written as its text form and set again gives the same configuration.
    omniloc::daemon::DaemonConfig back;
    for (const auto& k : omniloc::daemon::daemon_config_keys()) {
      const auto json = *k.write(c);
      const std::string text = json.is_string() ? json.get<std::string>() : json.dump();
      omniloc::daemon::set_daemon_key(back, k.name, text, "round trip");
    }
    fuzz_check(back == c,
               "a configuration from the command line does not read back from its own text");
  } catch (const omniloc::ConfigError& e) {
    fuzz_check(std::strstr(e.what(), "command line") != nullptr,
               "a ConfigError that does not name the command line");
  }
  return 0;
}
