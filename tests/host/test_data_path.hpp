// tests/data/<name> found from the working directory (the build directory) upwards; empty if
// absent.
#pragma once

#include <filesystem>
#include <string>

namespace omniloc::test {

inline std::filesystem::path test_data(const std::string& name) {
  for (auto dir = std::filesystem::current_path(); !dir.empty(); dir = dir.parent_path()) {
    const auto p = dir / "tests" / "data" / name;
    if (std::filesystem::exists(p)) return p;
    if (dir == dir.parent_path()) break;
  }
  return {};
}

}  // namespace omniloc::test
