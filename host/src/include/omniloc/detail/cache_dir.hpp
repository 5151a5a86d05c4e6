// Where omniloc keeps files it can rebuild at any time (feature databases): the user's cache
// directory of the XDG Base Directory Specification, never the build or source tree (an installed
// program has no build tree, and a source tree may be read-only or shared).
#pragma once

#include <filesystem>
#include <stdexcept>

namespace omniloc {

/// No usable cache directory in the environment; what() says which variables were looked at.
class CacheDirError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// `$XDG_CACHE_HOME/omniloc` when XDG_CACHE_HOME is set to an absolute path, else
/// `$HOME/.cache/omniloc` (the specification ignores a relative XDG_CACHE_HOME). Throws
/// CacheDirError when neither gives an absolute path. The directory is not created here.
/// The two arguments are the variables' values (nullptr = unset), so that the rule is testable.
[[nodiscard]] std::filesystem::path user_cache_dir(const char* xdg_cache_home, const char* home);

/// user_cache_dir() of this process's environment.
[[nodiscard]] std::filesystem::path user_cache_dir();

}  // namespace omniloc
