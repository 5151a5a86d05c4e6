// `omniloc builddb` end to end: the command writes a file that loads and equals the library's
// build for the same grid; bad usage gets exit code 2, a bad field name exit code 1.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <sys/wait.h>

#include "omniloc/feature_db.hpp"

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

}  // namespace
}  // namespace omniloc
