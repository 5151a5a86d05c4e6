#include "omniloc/detail/file_write.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>

namespace omniloc {

namespace fs = std::filesystem;

namespace {

// A new file `.<name>.tmp-<pid>-<n>` beside `path` (created, never an existing one followed): its
// descriptor, or -1 with errno set.
int create_temporary(const fs::path& path, fs::path& temp) {
  static std::atomic<unsigned> counter{0};
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::string name = ".";  // appended piece by piece: GCC 12 warns (-Wrestrict) on "." + s
    name += path.filename().string();
    name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    temp = path.parent_path() / name;
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  return -1;
}

bool write_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      return false;
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

}  // namespace

void write_file_replacing(const fs::path& path, std::initializer_list<std::string_view> parts) {
  fs::path temp;
  const int fd = create_temporary(path, temp);
  if (fd < 0) {
    throw FileWriteError(path.string() + ": cannot create the temporary file " + temp.string() +
                         " to write it: " + std::strerror(errno));
  }
  bool ok = true;
  for (const std::string_view part : parts)
    if (!(ok = write_all(fd, part))) break;
  if (ok) ok = ::fsync(fd) == 0;
  int error = errno;
  if (::close(fd) != 0 && ok) {
    ok = false;
    error = errno;
  }
  if (ok && ::rename(temp.c_str(), path.c_str()) != 0) {
    ok = false;
    error = errno;
  }
  if (!ok) {
    ::unlink(temp.c_str());
    throw FileWriteError(path.string() + ": write failed: " + std::strerror(error) +
                         " (nothing changed at that path; the partial temporary " + temp.string() +
                         " was removed)");
  }
}

}  // namespace omniloc
