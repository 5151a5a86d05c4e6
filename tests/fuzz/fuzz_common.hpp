// Shared pieces of the libFuzzer harnesses (tests/fuzz, docs/TESTING.md "Fuzzing").
//
// A harness feeds untrusted bytes to one real entry point of the library. The errors that entry
// point documents (its own exception types, naming the file or field) are expected and caught; any
// other exception escapes and aborts, and a crash, a sanitizer report, an allocation beyond
// libFuzzer's -malloc_limit_mb or a run beyond -timeout is a finding. fuzz_check() is for the
// properties a harness asserts about what the entry point returned.
#pragma once

#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace omniloc::fuzz {

/// Aborts (a finding) with the message when `ok` is false.
inline void fuzz_check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_check failed: %s\n", what);
    std::abort();
  }
}

/// A scratch file for readers that take a path: one per process (libFuzzer runs inputs one after
/// another in a process; -fork/-jobs workers are processes of their own), removed at exit.
class ScratchFile {
 public:
  explicit ScratchFile(std::string_view name) {
    dir_ = std::filesystem::temp_directory_path() / ("omniloc-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    path_ = dir_ / std::string(name);
  }
  ~ScratchFile() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  /// Replaces the file's content with `bytes`; returns its path.
  const std::filesystem::path& write(std::string_view bytes) const {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    fuzz_check(static_cast<bool>(out), "writing the scratch file");
    return path_;
  }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::filesystem::path path_;
};

}  // namespace omniloc::fuzz
