// Robot config files: the default file's values, and a clear error (file, field, why) for each
// kind of bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>

#include "omniloc/robot_config.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

const char* kValid = R"({"wheel_radius_cm": 5.0, "center_to_wheel_cm": 20.0, "motor_angle_deg": 45,
  "gear_ratio": 19, "counts_per_rev": 500, "decoding": 4)";

fs::path write_file(const std::string& body) {
  const auto* info = testing::UnitTest::GetInstance()->current_test_info();
  const fs::path p = fs::path(testing::TempDir()) / (std::string("robot_") + info->name() + ".json");
  std::ofstream(p) << body;
  return p;
}

// Loads `body` and returns the error text ("" if it loaded).
std::string error_of(const std::string& body) {
  const fs::path p = write_file(body);
  try {
    (void)load_robot_config(p);
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(p.string()), std::string::npos) << "error does not name the file: " << what;
    return what;
  }
  return "";
}

TEST(RobotConfig, DefaultFileLoadsWithTheDocumentedValues) {
  const RobotConfig c = load_named_robot_config("default");
  EXPECT_DOUBLE_EQ(c.wheel_radius_cm, 5.0);
  EXPECT_DOUBLE_EQ(c.center_to_wheel_cm, 20.0);
  EXPECT_DOUBLE_EQ(c.motor_angle_deg, 45.0);
  EXPECT_DOUBLE_EQ(c.gear_ratio, 19.0);
  EXPECT_EQ(c.counts_per_rev, 500);
  EXPECT_EQ(c.decoding, 4);
  EXPECT_DOUBLE_EQ(c.window_period_ms, 10.0);
  EXPECT_DOUBLE_EQ(c.clock_hz, 40.0e6);
  // One wheel turn = 500 x 4 x 19 counts (issue 7 contract).
  EXPECT_DOUBLE_EQ(counts_per_wheel_turn(c), 38000.0);
}

TEST(RobotConfig, RequiredOnlyFileTakesDefaultsForOptionalKeys) {
  const RobotConfig c = load_robot_config(write_file(std::string(kValid) + "}"));
  EXPECT_DOUBLE_EQ(c.window_period_ms, 10.0);
  EXPECT_DOUBLE_EQ(c.slip_threshold_cm_per_s, 5.0);
}

TEST(RobotConfig, BadValuesNameTheFieldAndWhy) {
  struct Case {
    std::string body;
    std::string must_contain;
  };
  const std::string base = R"("center_to_wheel_cm": 20.0, "motor_angle_deg": 45, "gear_ratio": 19, "counts_per_rev": 500)";
  const Case cases[] = {
      {"{\"wheel_radius_cm\": -5.0, " + base + ", \"decoding\": 4}", "field 'wheel_radius_cm': must be > 0 (got -5)"},
      {"{\"wheel_radius_cm\": 5.0, " + base + ", \"decoding\": 3}", "field 'decoding': unknown quadrature decoding mode: must be 1, 2 or 4 (got 3)"},
      {R"({"wheel_radius_cm": 5.0, "center_to_wheel_cm": 20.0, "motor_angle_deg": 45, "gear_ratio": 19, "counts_per_rev": 0, "decoding": 4})",
       "field 'counts_per_rev': must be a positive number of encoder cycles per motor turn (got 0)"},
      {R"({"wheel_radius_cm": 5.0, "center_to_wheel_cm": 20.0, "motor_angle_deg": 90, "gear_ratio": 19, "counts_per_rev": 500, "decoding": 4})",
       "field 'motor_angle_deg': must be strictly between 0 and 90"},
      {R"({"wheel_radius_cm": 5.0, "center_to_wheel_cm": 20.0, "motor_angle_deg": 45, "gear_ratio": 0, "counts_per_rev": 500, "decoding": 4})",
       "field 'gear_ratio': must be > 0"},
      {R"({"wheel_radius_cm": 5.0, "motor_angle_deg": 45, "gear_ratio": 19, "counts_per_rev": 500, "decoding": 4})",
       "field 'center_to_wheel_cm': missing (required)"},
      {std::string(kValid) + R"(, "wheel_radius": 4})", "field 'wheel_radius': unknown field (known fields: wheel_radius_cm"},
      {R"({"wheel_radius_cm": "five", "center_to_wheel_cm": 20.0, "motor_angle_deg": 45, "gear_ratio": 19, "counts_per_rev": 500, "decoding": 4})",
       "field 'wheel_radius_cm': must be a number"},
      {R"({"wheel_radius_cm": 5, "center_to_wheel_cm": 20.0, "motor_angle_deg": 45, "gear_ratio": 19, "counts_per_rev": 500.5, "decoding": 4})",
       "field 'counts_per_rev': must be an integer"},
      {std::string(kValid) + R"(, "window_period_ms": -10})", "field 'window_period_ms': must be > 0"},
      {std::string(kValid) + R"(, "odometry_noise_fraction": -0.1})", "field 'odometry_noise_fraction': must be >= 0"},
      {R"([1, 2, 3])", "not a valid JSON object"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.body);
    const std::string err = error_of(c.body);
    EXPECT_NE(err.find(c.must_contain), std::string::npos) << "got: " << err;
  }
}

TEST(RobotConfig, MissingAndMalformedFilesAreNamed) {
  try {
    (void)load_robot_config("/nonexistent/robot.json");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/robot.json: no such file");
  }
  const std::string err = error_of(R"({"wheel_radius_cm": 5.0, )");
  EXPECT_NE(err.find("not a valid JSON object"), std::string::npos) << err;
  EXPECT_THROW((void)load_named_robot_config("no_such_robot"), std::runtime_error);
}

TEST(RobotConfig, ParsesTheRobotBlockOfARecordingMetaFile) {
  const std::string meta = R"({"field": "fira-robosot", "robot": {"wheel_radius_cm": 4.5, "center_to_wheel_cm": 18.0,
    "motor_angle_deg": 45, "gear_ratio": 14, "counts_per_rev": 512, "decoding": 2}})";
  cv::FileStorage fs(meta, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_JSON);
  const RobotConfig c = parse_robot_config(fs["robot"], "rec/meta.json: robot");
  EXPECT_DOUBLE_EQ(c.wheel_radius_cm, 4.5);
  EXPECT_EQ(c.counts_per_rev, 512);
  EXPECT_EQ(c.decoding, 2);
  EXPECT_DOUBLE_EQ(counts_per_wheel_turn(c), 512.0 * 2.0 * 14.0);
  try {
    (void)parse_robot_config(fs["nothing"], "rec/meta.json: robot");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rec/meta.json: robot"), std::string::npos);
  }
}

}  // namespace
}  // namespace omniloc
