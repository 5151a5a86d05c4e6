// Locating the project's shared data files (common/fields/*.json, common/cameras/*.json) from a
// short name such as "fira-robosot", so that programs and tests run from any build directory.
#pragma once

#include <filesystem>
#include <string>

namespace omniloc {

/// Resolves `name_or_path` inside the data folder `kind` ("fields" or "cameras"):
/// an existing file path is returned as is; otherwise `<dir>/common/<kind>/<name>.json` is looked
/// up in $OMNILOC_DATA_DIR (as `<dir>/<kind>/<name>.json`), then in the current directory and its
/// parents, then in the executable's directory and its parents. Throws std::runtime_error listing
/// the places searched when nothing matches.
[[nodiscard]] std::filesystem::path resolve_data_file(const std::string& kind,
                                                      const std::string& name_or_path);

}  // namespace omniloc
