#include "omniloc/version.hpp"

#include <cstdio>

#include "omniloc/regmap.hpp"
#include "omniloc_git_revision.hpp"  // generated at build time (cmake/git_revision.cmake)

namespace omniloc {

std::string_view project_version() {
  return OMNILOC_PROJECT_VERSION;
}

std::string_view git_revision() {
  return OMNILOC_GIT_REVISION;
}

std::string version_line(std::string_view program) {
  const auto v = regmap::kVersionValue;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.*s %.*s (register map %u.%u.%u, board ID 0x%08X, git %.*s)",
                static_cast<int>(program.size()), program.data(),
                static_cast<int>(project_version().size()), project_version().data(),
                regmap::kVersionMajor.get(v), regmap::kVersionMinor.get(v),
                regmap::kVersionPatch.get(v), regmap::kIdValue,
                static_cast<int>(git_revision().size()), git_revision().data());
  return buf;
}

}  // namespace omniloc
