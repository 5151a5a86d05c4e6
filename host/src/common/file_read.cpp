#include "omniloc/detail/file_read.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

namespace omniloc {

namespace fs = std::filesystem;

namespace {
[[noreturn]] void refuse(const fs::path& path, const std::string& why) {
  throw FileReadError(path.string() + ": " + why);
}
}  // namespace

std::uintmax_t regular_file_size(const fs::path& path, std::uintmax_t max_bytes,
                                 std::string_view what) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) refuse(path, "no such file");
  if (fs::is_directory(st)) refuse(path, "is a directory, not a " + std::string(what));
  if (!fs::is_regular_file(st))
    refuse(path, "not a regular file (a device or a pipe?), not a " + std::string(what));
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) refuse(path, "cannot read its size (" + ec.message() + ")");
  if (size > max_bytes) {
    refuse(path, std::to_string(size) + " bytes, more than a " + std::string(what) +
                     " can be (at most " + std::to_string(max_bytes) + ")");
  }
  return size;
}

std::string read_file_bounded(const fs::path& path, std::uintmax_t max_bytes,
                              std::string_view what) {
  const std::uintmax_t size = regular_file_size(path, max_bytes, what);
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"),
                                                          &std::fclose);
  if (!f) refuse(path, std::string("cannot open (") + std::strerror(errno) + ")");
  std::string out;
  out.reserve(static_cast<std::size_t>(size));
  // Read to the end rather than `size` bytes (the file may change meanwhile), but never past the
  // cap.
  char buf[65536];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f.get())) > 0;) {
    if (out.size() + n > max_bytes)
      refuse(path, "grew beyond " + std::to_string(max_bytes) + " bytes while being read");
    out.append(buf, n);
  }
  if (std::ferror(f.get())) refuse(path, std::string("read failed (") + std::strerror(errno) + ")");
  return out;
}

}  // namespace omniloc
