// Locating the shared data files (common/<kind>/<name>.json) from a short name, so that programs
// and tests run from any build directory and installed programs from any prefix. Searched in order:
// $OMNILOC_DATA_DIR, common/ in the working directory and its parents, <exe>/../share/omniloc (the
// installed layout), common/ beside the executable and its parents.
#include <algorithm>
#include <cstdlib>
#include <system_error>
#include <vector>

#include "omniloc/config.hpp"

namespace omniloc::config {

namespace fs = std::filesystem;

namespace {
void add_with_parents(fs::path dir, std::vector<fs::path>& out) {
  std::error_code ec;
  dir = fs::weakly_canonical(dir, ec);
  if (ec) return;
  while (true) {
    out.push_back(dir / "common");
    if (!dir.has_parent_path() || dir.parent_path() == dir) break;
    dir = dir.parent_path();
  }
}
}  // namespace

fs::path resolve_data_file(const std::string& kind, const std::string& name_or_path) {
  std::error_code ec;
  if (fs::is_regular_file(name_or_path, ec)) return fs::path(name_or_path);
  if (name_or_path.find('/') != std::string::npos || name_or_path.ends_with(".json")) {
    // A path, not a name: it must be a file.
    if (fs::is_directory(name_or_path, ec))
      throw ConfigError(name_or_path + ": is a directory, not a JSON file");
    if (fs::exists(name_or_path, ec))
      throw ConfigError(name_or_path +
                        ": not a regular file (a device or a pipe?), not a JSON file");
    throw ConfigError(name_or_path + ": no such file");
  }
  std::vector<fs::path> roots;
  if (const char* env = std::getenv("OMNILOC_DATA_DIR"); env != nullptr && *env != '\0') {
    roots.emplace_back(env);
  }
  add_with_parents(fs::current_path(ec), roots);
  const fs::path exe_dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
  // Installed programs (bin/) find the data under ../share/omniloc (cmake --install).
  if (!exe_dir.empty()) {
    const fs::path installed = fs::weakly_canonical(exe_dir / ".." / "share" / "omniloc", ec);
    if (!ec) roots.push_back(installed);
  }
  add_with_parents(exe_dir, roots);
  std::string searched;
  std::vector<fs::path> seen;
  for (const auto& root : roots) {
    if (std::find(seen.begin(), seen.end(), root) != seen.end()) continue;
    seen.push_back(root);
    const fs::path candidate = root / kind / (name_or_path + ".json");
    if (fs::is_regular_file(candidate, ec)) return candidate;
    if (!searched.empty()) searched += ", ";
    searched += (root / kind).string();
  }
  throw ConfigError("no " + kind + " file named '" + name_or_path + "' (searched " + searched +
                    "; set OMNILOC_DATA_DIR to the folder holding " + kind + "/)");
}

}  // namespace omniloc::config
