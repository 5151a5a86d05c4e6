// `omniloc builddb` end to end: the command writes a file that loads and equals the library's
// build for the same grid; bad usage gets exit code 2, a bad field name exit code 1.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <sys/wait.h>

#include "omniloc/feature_db.hpp"
#include "run_command.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

int run(const std::string& args) {
  // Tests run in the build directory (gtest_discover_tests WORKING_DIRECTORY), where bin/ is.
  const int status = std::system(("./bin/omniloc builddb " + args + " > /dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(BuildDbCommand, WritesTheSameDatabaseAsTheLibrary) {
  if (!fs::exists("bin/omniloc")) GTEST_SKIP() << "bin/omniloc not built in " << fs::current_path();
  const std::string out =
      (fs::temp_directory_path() / ("omniloc_builddb_" + std::to_string(::getpid()) + ".db"))
          .string();
  ASSERT_EQ(run("--field fira-robosot --camera default --step 25 --threads 1 --out " + out), 0);
  const FieldGeometry field = load_field("fira-robosot");
  const CameraModel camera = load_camera("default");
  const FeatureDb loaded = load_feature_db(out, field, camera);
  const FeatureDb built = build_feature_db(field, camera, GridSpec::covering(field, 25.0), {}, 1);
  EXPECT_EQ(loaded.grid.nx, 30);
  EXPECT_EQ(loaded.grid.ny, 22);
  EXPECT_EQ(loaded.features, built.features);
  fs::remove(out);
  EXPECT_EQ(run("--step 25"), 2);                // no --out
  EXPECT_EQ(run("--step ten --out " + out), 2);  // not a number
  EXPECT_EQ(run("--bogus 1 --out " + out), 2);   // unknown option
  EXPECT_EQ(run("--field no-such-field --out " + out), 1);
  EXPECT_FALSE(fs::exists(out));
}

// `omniloc builddb` with its output and stderr (run in the build directory, as above), under a
// shell prefix (a file size limit).
int run_logged(const std::string& prefix, const std::string& args, const fs::path& log,
               std::string& output) {
  return test::run_command(prefix + "./bin/omniloc builddb " + args, log, output);
}

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Issue (hostile input): a full disk during `omniloc builddb` left a partial database at --out,
// which replay and locate then refused to overwrite until removed by hand; and --out overwrote
// without a word a file that is not a database, which replay and locate refuse to do. The disk
// fills up as a file size limit (prlimit --fsize, binding root too; SIGXFSZ ignored, so write()
// fails part-way with EFBIG as a full disk's does with ENOSPC).
TEST(BuildDbCommand, AFullDiskLeavesNoPartialFileAndAFileNotADatabaseIsNotOverwritten) {
  if (!fs::exists("bin/omniloc")) GTEST_SKIP() << "bin/omniloc not built in " << fs::current_path();
  if (std::system("command -v prlimit > /dev/null") != 0) GTEST_SKIP() << "no prlimit";
  const fs::path dir =
      fs::temp_directory_path() / ("omniloc_builddb_full_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "db");
  const fs::path out = dir / "db" / "features.db";
  const std::string args = "--step 25 --threads 1 --out " + out.string();
  std::string log;
  EXPECT_EQ(run_logged("trap '' XFSZ; prlimit --fsize=65536 ", args, dir / "log.txt", log), 1);
  EXPECT_NE(log.find(out.string() + ": write failed: " + std::strerror(EFBIG)), std::string::npos)
      << log;
  EXPECT_TRUE(fs::is_empty(dir / "db"))
      << "left behind: " << fs::directory_iterator(dir / "db")->path();
  // The path is not blocked: the next run writes it.
  EXPECT_EQ(run_logged("", args, dir / "log.txt", log), 0) << log;
  EXPECT_EQ(
      load_feature_db(out.string(), load_field("fira-robosot"), load_camera("default")).grid.nx,
      30);

  // A file that is not a database is left alone, with replay's and locate's words.
  const fs::path notes = dir / "db" / "notes.txt";
  std::ofstream(notes) << "my notes\n";
  EXPECT_EQ(run_logged("", "--step 25 --out " + notes.string(), dir / "log.txt", log), 1);
  EXPECT_NE(
      log.find(notes.string() + ": exists and is not an omniloc feature database; not overwriting"),
      std::string::npos)
      << log;
  EXPECT_EQ(read_all(notes), "my notes\n");
  // An older database may be overwritten.
  EXPECT_EQ(run_logged("", "--step 50 --threads 1 --out " + out.string(), dir / "log.txt", log), 0)
      << log;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omniloc
