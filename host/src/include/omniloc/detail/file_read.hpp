// Bounded file reads: every file omniloc reads (config JSON, meta.json, recording CSVs, feature
// databases) goes through here, so that a directory, a device (/dev/zero never ends), a pipe or a
// file far larger than its kind can be is refused with its path before anything is read into
// memory, instead of reading until std::bad_alloc or failing with a library message that does
// not say which file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace omniloc {

/// A file that cannot be read as asked; what() starts with the path.
class FileReadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Caps for each kind of file (far above any real one, far below the machine's memory).
inline constexpr std::uintmax_t kMaxJsonFileBytes = 16u << 20;  // config, camera, field, meta.json
inline constexpr std::uintmax_t kMaxCsvFileBytes = 1024u
                                                   << 20;  // a recording's CSV (hours at 100 Hz)

/// The size of `path` if it is a regular file (symlinks followed) of at most `max_bytes`; throws
/// FileReadError "<path>: <why>" when it is missing, a directory, not a regular file, or larger.
/// `what` names the kind of file in the message ("JSON file", "feature database").
[[nodiscard]] std::uintmax_t regular_file_size(const std::filesystem::path& path,
                                               std::uintmax_t max_bytes, std::string_view what);

/// The whole content of a regular file of at most `max_bytes` (checked before reading and again
/// while reading, in case it grows); throws FileReadError naming the path.
[[nodiscard]] std::string read_file_bounded(const std::filesystem::path& path,
                                            std::uintmax_t max_bytes, std::string_view what);

}  // namespace omniloc
