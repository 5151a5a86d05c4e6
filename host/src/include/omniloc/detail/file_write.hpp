// Whole-file writes that never leave a partial file at the path: the bytes go to a temporary file
// beside it, flushed to disk, then renamed into place. A failure part-way (a full disk) leaves
// whatever was at the path before as it was and removes the temporary, so the next run is not
// blocked by a truncated file it refuses to overwrite.
#pragma once

#include <filesystem>
#include <initializer_list>
#include <stdexcept>
#include <string_view>

namespace omniloc {

/// A file that could not be written; what() starts with the path.
class FileWriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes `parts`, one after another, as the whole content of `path` (replacing a file there only
/// once all of it is on disk). The temporary is `.<name>.tmp-<pid>-<n>` in the same directory.
/// Throws FileWriteError "<path>: <why>" with the system's error (e.g. "No space left on device").
void write_file_replacing(const std::filesystem::path& path,
                          std::initializer_list<std::string_view> parts);

}  // namespace omniloc
