// What a program was built from: the project version, the register-map version it speaks and the
// git revision of the tree (`--version` of every program, `omniloc version`).
#pragma once

#include <string>
#include <string_view>

namespace omniloc {

/// "0.1.0" (CMake's project version).
[[nodiscard]] std::string_view project_version();
/// `git describe --always --dirty` of the source tree at build time, or "unknown".
[[nodiscard]] std::string_view git_revision();
/// "PROGRAM 0.1.0 (register map 0.1.0, board ID 0x4F4D4E4C, git 853427d...)".
[[nodiscard]] std::string version_line(std::string_view program);

}  // namespace omniloc
