#include "omniloc/detail/cache_dir.hpp"

#include <cstdlib>
#include <string>

namespace omniloc {

namespace {

bool absolute(const char* value) {
  return value != nullptr && value[0] == '/';
}

}  // namespace

std::filesystem::path user_cache_dir(const char* xdg_cache_home, const char* home) {
  if (absolute(xdg_cache_home)) return std::filesystem::path(xdg_cache_home) / "omniloc";
  if (absolute(home)) return std::filesystem::path(home) / ".cache" / "omniloc";
  const auto shown = [](const char* v) {
    return v == nullptr ? std::string("unset") : "'" + std::string(v) + "'";
  };
  throw CacheDirError("no cache directory: XDG_CACHE_HOME is " + shown(xdg_cache_home) +
                      " and HOME is " + shown(home) +
                      " (one of them must be an absolute path; or name the file with --db)");
}

std::filesystem::path user_cache_dir() {
  return user_cache_dir(std::getenv("XDG_CACHE_HOME"), std::getenv("HOME"));
}

}  // namespace omniloc
