// Robot config files: the shipped default file is the struct's defaults (every key), a file setting
// every key to a non-default value lands in every member (expected values by hand), and a clear
// error (file, field path, why, value) for each kind of bad input.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "config_test_util.hpp"
#include "omniloc/config_reader.hpp"
#include "omniloc/robot_config.hpp"

namespace omniloc {
namespace {

using test::error_of;

// Every key of RobotConfig, by hand: the six of the recording contract, then the optional ones.
const std::vector<std::string> kEveryKey = {
    "wheel_radius_cm",  "center_to_wheel_cm",         "motor_angle_deg",     "gear_ratio",
    "counts_per_rev",   "decoding",                   "window_period_ms",    "clock_hz",
    "slip_threshold_cm_per_s", "wheel_noise_cm_per_sqrt_cm", "max_accel_cm_per_s2", "odometry_noise_fraction",
    "gyro_arw_deg_per_sqrt_s"};

const std::string kEveryKeyJson = R"({
  "wheel_radius_cm": 4.5,
  "center_to_wheel_cm": 18.25,
  "motor_angle_deg": 30,
  "gear_ratio": 14,
  "counts_per_rev": 512,
  "decoding": 2,
  "window_period_ms": 20,
  "clock_hz": 12000000,
  "slip_threshold_cm_per_s": 7.5,
  "wheel_noise_cm_per_sqrt_cm": 0.02,
  "max_accel_cm_per_s2": 350,
  "odometry_noise_fraction": 0.01,
  "gyro_arw_deg_per_sqrt_s": 0.03
})";

const char* kRequiredOnly = R"({"wheel_radius_cm": 5.0, "center_to_wheel_cm": 20.0, "motor_angle_deg": 45,
  "gear_ratio": 19, "counts_per_rev": 500, "decoding": 4})";

TEST(RobotConfig, ShippedDefaultFileIsTheStructDefaultsEveryKey) {
  const auto path = resolve_data_file("robots", "default");
  EXPECT_EQ(test::keys_of(test::read_json(path)), kEveryKey);
  const RobotConfig c = load_named_robot_config("default");
  EXPECT_TRUE(c == RobotConfig{});
  // The documented values (docs/ODOMETRY.md): one wheel turn = 500 x 4 x 19 counts (issue 7).
  EXPECT_DOUBLE_EQ(counts_per_wheel_turn(c), 38000.0);
  EXPECT_DOUBLE_EQ(c.clock_hz, 40.0e6);
}

TEST(RobotConfig, EveryKeyReachesItsMember) {
  const auto p = test::write_file("every.json", kEveryKeyJson);
  EXPECT_EQ(test::keys_of(test::read_json(p)), kEveryKey);
  const RobotConfig c = load_robot_config(p);
  EXPECT_EQ(c.wheel_radius_cm, 4.5);
  EXPECT_EQ(c.center_to_wheel_cm, 18.25);
  EXPECT_EQ(c.motor_angle_deg, 30.0);
  EXPECT_EQ(c.gear_ratio, 14.0);
  EXPECT_EQ(c.counts_per_rev, 512);
  EXPECT_EQ(c.decoding, 2);
  EXPECT_EQ(c.window_period_ms, 20.0);
  EXPECT_EQ(c.clock_hz, 12.0e6);
  EXPECT_EQ(c.slip_threshold_cm_per_s, 7.5);
  EXPECT_EQ(c.wheel_noise_cm_per_sqrt_cm, 0.02);
  EXPECT_EQ(c.max_accel_cm_per_s2, 350.0);
  EXPECT_EQ(c.odometry_noise_fraction, 0.01);
  EXPECT_EQ(c.gyro_arw_deg_per_sqrt_s, 0.03);
}

TEST(RobotConfig, EachOptionalKeyOfTheFullFileMatters) {
  const RobotConfig full = load_robot_config(test::write_file("every.json", kEveryKeyJson));
  const auto json = test::read_json(test::write_file("every.json", kEveryKeyJson));
  for (std::size_t i = 6; i < kEveryKey.size(); ++i) {
    auto without = json;
    without.erase(kEveryKey[i]);
    EXPECT_FALSE(load_robot_config(test::write_file("without.json", without.dump())) == full)
        << kEveryKey[i] << " made no difference";
  }
}

TEST(RobotConfig, RequiredOnlyFileTakesDefaultsForOptionalKeys) {
  const RobotConfig c = load_robot_config(test::write_file("required.json", kRequiredOnly));
  EXPECT_TRUE(c == RobotConfig{});
}

TEST(RobotConfig, BadValuesNameTheFileFieldAndValue) {
  const std::string v = kRequiredOnly;
  test::expect_errors(
      [](const std::string& f) { (void)load_robot_config(f); },
      {
          {test::replaced(v, "\"wheel_radius_cm\": 5.0", "\"wheel_radius_cm\": -5.0"), "wheel_radius_cm",
           "must be > 0 (got -5)"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 3"), "decoding",
           "unknown quadrature decoding mode: must be 1, 2 or 4 (got 3)"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 0"), "counts_per_rev",
           "must be a positive number of encoder cycles per motor turn (got 0)"},
          {test::replaced(v, "\"motor_angle_deg\": 45", "\"motor_angle_deg\": 90"), "motor_angle_deg",
           "must be strictly between 0 and 90 degrees, or equation (9) loses rank (got 90)"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": 0"), "gear_ratio", "must be > 0 (got 0)"},
          {test::replaced(v, "\"center_to_wheel_cm\": 20.0, ", ""), "center_to_wheel_cm", "missing (required)"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"wheel_radius\": 4"), "wheel_radius",
           "unknown key (known keys: wheel_radius_cm, "},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"decoding\": 2"), "decoding", "duplicate key"},
          {test::replaced(v, "\"wheel_radius_cm\": 5.0", "\"wheel_radius_cm\": \"five\""), "wheel_radius_cm",
           "must be a number, not a string (got \"five\")"},
          {test::replaced(v, "\"wheel_radius_cm\": 5.0", "\"wheel_radius_cm\": true"), "wheel_radius_cm",
           "must be a number, not a boolean (got true)"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 500.5"), "counts_per_rev",
           "must be an integer"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 500.0"), "counts_per_rev",
           "must be an integer"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 5000000000"), "counts_per_rev",
           "out of range"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": NaN"), "gear_ratio", "not valid JSON"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": Infinity"), "gear_ratio", "not valid JSON"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": 1e400"), "gear_ratio",
           "number out of range: beyond a double (got 1e400)"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"window_period_ms\": -10"), "window_period_ms",
           "must be > 0 (got -10)"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"odometry_noise_fraction\": -0.1"),
           "odometry_noise_fraction", "must be >= 0 (got -0.1)"},
          {R"([1, 2, 3])", "", "must be an object, not an array"},
          {R"({"wheel_radius_cm": 5.0, )", "", "not valid JSON"},
      });
}

TEST(RobotConfig, MissingFileAndDirectoryAreNamed) {
  EXPECT_EQ(error_of([] { (void)load_robot_config("/nonexistent/robot.json"); }), "/nonexistent/robot.json: no such file");
  const auto dir = test::temp_dir();
  EXPECT_EQ(error_of([&] { (void)load_robot_config(dir); }), dir.string() + ": is a directory, not a JSON file");
  EXPECT_EQ(error_of([&] { (void)load_named_robot_config(dir.string()); }),
            dir.string() + ": is a directory, not a JSON file");
  EXPECT_THROW((void)load_named_robot_config("no_such_robot"), ConfigError);
}

TEST(RobotConfig, ParsesTheRobotBlockOfARecordingMetaFile) {
  const config::Document meta = config::parse_json_text(
      R"({"field": "fira-robosot", "robot": {"wheel_radius_cm": 4.5, "center_to_wheel_cm": 18.0,
          "motor_angle_deg": 45, "gear_ratio": 14, "counts_per_rev": 512, "decoding": 2}})",
      "rec/meta.json");
  const RobotConfig c = parse_robot_config(meta.root() / "robot");
  EXPECT_DOUBLE_EQ(c.wheel_radius_cm, 4.5);
  EXPECT_EQ(c.counts_per_rev, 512);
  EXPECT_EQ(c.decoding, 2);
  EXPECT_DOUBLE_EQ(counts_per_wheel_turn(c), 512.0 * 2.0 * 14.0);
  const config::Document bad = config::parse_json_text(
      R"({"robot": {"wheel_radius_cm": 4.5, "center_to_wheel_cm": 18.0, "motor_angle_deg": 45, "gear_ratio": 14,
          "counts_per_rev": 512, "decoding": 3}})",
      "rec/meta.json");
  EXPECT_EQ(error_of([&] { (void)parse_robot_config(bad.root() / "robot"); }),
            "rec/meta.json:robot.decoding: unknown quadrature decoding mode: must be 1, 2 or 4 (got 3)");
}

}  // namespace
}  // namespace omniloc
