// Test helper: runs a command line through the shell, its stdout and stderr into a log file.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace omniloc::test {

/// The exit status of `cmd` (-1 when it did not exit), its stdout+stderr in `output`.
inline int run_command(const std::string& cmd, const std::filesystem::path& log,
                       std::string& output) {
  const int status = std::system((cmd + " >" + log.string() + " 2>&1").c_str());
  std::ifstream in(log);
  std::ostringstream os;
  os << in.rdbuf();
  output = os.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace omniloc::test
