// Bounded file reads (file_read.hpp): what is not a regular file, or is larger than its kind can
// be, is refused with its path before anything is read (issue 16 item 1: `--database /dev/zero`
// read until std::bad_alloc, `--database /tmp` failed with "basic_filebuf::underflow ... Is a
// directory" and no path). Also the callers: the config reader and the recording CSV readers.
#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <string>

#include "config_test_util.hpp"
#include "omniloc/detail/config_reader.hpp"
#include "omniloc/detail/file_read.hpp"
#include "omniloc/recording.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;
using test::error_of;

TEST(FileRead, ReadsAWholeRegularFileByteForByte) {
  const fs::path dir = test::temp_dir();
  const fs::path p = dir / "a.bin";
  std::string content(200000, 'x');
  content[0] = '\0';
  content[199999] = '\n';
  std::ofstream(p, std::ios::binary) << content;
  EXPECT_EQ(read_file_bounded(p, 200000, "test file"), content);
  EXPECT_EQ(regular_file_size(p, 200000, "test file"), 200000u);
}

TEST(FileRead, RefusesMissingDirectoriesDevicesAndOversizedFilesByPath) {
  const fs::path dir = test::temp_dir();
  EXPECT_EQ(error_of([&] { (void)read_file_bounded(dir / "none", 10, "test file"); }),
            (dir / "none").string() + ": no such file");
  EXPECT_EQ(error_of([&] { (void)read_file_bounded(dir, 10, "test file"); }),
            dir.string() + ": is a directory, not a test file");
  // /dev/zero never ends: refused before a byte is read.
  EXPECT_EQ(error_of([] { (void)read_file_bounded("/dev/zero", 10, "test file"); }),
            "/dev/zero: not a regular file (a device or a pipe?), not a test file");
  // A symlink to a device is the device.
  fs::create_symlink("/dev/zero", dir / "link");
  EXPECT_EQ(
      error_of([&] { (void)read_file_bounded(dir / "link", 10, "test file"); }),
      (dir / "link").string() + ": not a regular file (a device or a pipe?), not a test file");
  std::ofstream(dir / "big") << std::string(11, 'x');
  EXPECT_EQ(error_of([&] { (void)read_file_bounded(dir / "big", 10, "test file"); }),
            (dir / "big").string() + ": 11 bytes, more than a test file can be (at most 10)");
}

TEST(FileRead, ConfigReaderRefusesADeviceWithItsPath) {
  // Before: parse_json_file("/dev/zero") read until std::bad_alloc.
  EXPECT_EQ(error_of([] { (void)config::parse_json_file("/dev/zero"); }),
            "/dev/zero: not a regular file (a device or a pipe?), not a JSON file");
  // A path to a device given where a data file is expected: named as such, not "no such file".
  EXPECT_EQ(error_of([] { (void)resolve_data_file("fields", "/dev/zero"); }),
            "/dev/zero: not a regular file (a device or a pipe?), not a JSON file");
}

TEST(FileRead, RecordingCsvThatIsADeviceIsRefusedWithItsPath) {
  // Before: std::getline over /dev/zero grew one line until std::bad_alloc.
  const fs::path dir = test::temp_dir();
  fs::create_symlink("/dev/zero", dir / "encoders.csv");
  EXPECT_EQ(error_of([&] { (void)read_encoders_csv(dir / "encoders.csv"); }),
            (dir / "encoders.csv").string() +
                ": not a regular file (a device or a pipe?), not a CSV file");
}

}  // namespace
}  // namespace omniloc
