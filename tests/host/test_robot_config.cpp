// Robot config files: the shipped default file is the struct's defaults (every key), a file setting
// every key to a non-default value lands in every member (expected values by hand), and a clear
// error (file, field path, why, value) for each kind of bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "config_test_util.hpp"
#include "omniloc/board_session.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/detail/config_reader.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc_sim/reference_board.hpp"
#include "omniloc_sim/uart_side.hpp"

namespace omniloc {
namespace {

using test::error_of;

// Every key of RobotConfig, by hand: the six of the recording contract, then the optional ones.
const std::vector<std::string> kEveryKey = {"wheel_radius_cm",         "center_to_wheel_cm",
                                            "motor_angle_deg",         "gear_ratio",
                                            "counts_per_rev",          "decoding",
                                            "slip_threshold_cm_per_s", "wheel_noise_cm_per_sqrt_cm",
                                            "max_accel_cm_per_s2",     "max_yaw_rate_deg_per_s",
                                            "odometry_noise_fraction", "gyro_arw_deg_per_sqrt_s"};

const std::string kEveryKeyJson = R"({
  "wheel_radius_cm": 4.5,
  "center_to_wheel_cm": 18.25,
  "motor_angle_deg": 30,
  "gear_ratio": 14,
  "counts_per_rev": 512,
  "decoding": 2,
  "slip_threshold_cm_per_s": 7.5,
  "wheel_noise_cm_per_sqrt_cm": 0.02,
  "max_accel_cm_per_s2": 350,
  "max_yaw_rate_deg_per_s": 900,
  "odometry_noise_fraction": 0.01,
  "gyro_arw_deg_per_sqrt_s": 0.03
})";

const char* kRequiredOnly =
    R"({"wheel_radius_cm": 5.0, "center_to_wheel_cm": 20.0, "motor_angle_deg": 45,
  "gear_ratio": 19, "counts_per_rev": 500, "decoding": 4})";

TEST(RobotConfig, ShippedDefaultFileIsTheStructDefaultsEveryKey) {
  const auto path = resolve_data_file("robots", "default");
  EXPECT_EQ(test::keys_of(test::read_json(path)), kEveryKey);
  const RobotConfig c = load_named_robot_config("default");
  EXPECT_TRUE(c == RobotConfig{});
  // The documented values (docs/ODOMETRY.md): one wheel turn = 500 x 4 x 19 counts (issue 7).
  EXPECT_DOUBLE_EQ(counts_per_wheel_turn(c), 38000.0);
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
  EXPECT_EQ(c.slip_threshold_cm_per_s, 7.5);
  EXPECT_EQ(c.wheel_noise_cm_per_sqrt_cm, 0.02);
  EXPECT_EQ(c.max_accel_cm_per_s2, 350.0);
  EXPECT_EQ(c.max_yaw_rate_deg_per_s, 900.0);
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
          {test::replaced(v, "\"wheel_radius_cm\": 5.0", "\"wheel_radius_cm\": -5.0"),
           "wheel_radius_cm", "must be > 0 (got -5)"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"max_yaw_rate_deg_per_s\": 1"),
           "max_yaw_rate_deg_per_s", "must be in [10, 36000] deg/s (got 1)"},
          {test::replaced(v, "\"decoding\": 4",
                          "\"decoding\": 4, \"max_yaw_rate_deg_per_s\": 1e300"),
           "max_yaw_rate_deg_per_s", "(got 1e+300)"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 3"), "decoding",
           "unknown quadrature decoding mode: must be 1, 2 or 4 (got 3)"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 0"), "counts_per_rev",
           "must be a positive number of encoder cycles per motor turn (got 0)"},
          {test::replaced(v, "\"motor_angle_deg\": 45", "\"motor_angle_deg\": 90"),
           "motor_angle_deg",
           "must be strictly between 0 and 90 degrees, or equation (9) loses rank (got 90)"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": 0"), "gear_ratio",
           "must be > 0 (got 0)"},
          {test::replaced(v, "\"center_to_wheel_cm\": 20.0, ", ""), "center_to_wheel_cm",
           "missing (required)"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"wheel_radius\": 4"),
           "wheel_radius", "unknown key (known keys: wheel_radius_cm, "},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"decoding\": 2"), "decoding",
           "duplicate key"},
          {test::replaced(v, "\"wheel_radius_cm\": 5.0", "\"wheel_radius_cm\": \"five\""),
           "wheel_radius_cm", "must be a number, not a string (got \"five\")"},
          {test::replaced(v, "\"wheel_radius_cm\": 5.0", "\"wheel_radius_cm\": true"),
           "wheel_radius_cm", "must be a number, not a boolean (got true)"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 500.5"),
           "counts_per_rev", "must be an integer"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 500.0"),
           "counts_per_rev", "must be an integer"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 5000000000"),
           "counts_per_rev", "out of range"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": NaN"), "gear_ratio",
           "not valid JSON"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": Infinity"), "gear_ratio",
           "not valid JSON"},
          {test::replaced(v, "\"gear_ratio\": 19", "\"gear_ratio\": 1e400"), "gear_ratio",
           "number out of range: beyond a double (got 1e400)"},
          // The window period and the board clock are the board's (its PERIOD register and the
          // register map's tick rate), no longer robot settings: a file that still sets them is
          // refused naming the key.
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"window_period_ms\": 10"),
           "window_period_ms", "unknown key"},
          {test::replaced(v, "\"decoding\": 4", "\"decoding\": 4, \"clock_hz\": 40000000"),
           "clock_hz", "unknown key"},
          {test::replaced(v, "\"decoding\": 4",
                          "\"decoding\": 4, \"slip_threshold_cm_per_s\": 1e9"),
           "slip_threshold_cm_per_s", "must be at most 10000 cm/s (got 1000000000)"},
          {test::replaced(v, "\"wheel_radius_cm\": 5.0", "\"wheel_radius_cm\": 1e9"),
           "wheel_radius_cm", "must be at most 100 cm (got 1000000000)"},
          {test::replaced(v, "\"center_to_wheel_cm\": 20.0", "\"center_to_wheel_cm\": 1e9"),
           "center_to_wheel_cm", "must be at most 1000 cm"},
          {test::replaced(v, "\"counts_per_rev\": 500", "\"counts_per_rev\": 2000000000"),
           "counts_per_rev", "must be at most 1000000 (got 2000000000)"},
          {test::replaced(v, "\"decoding\": 4",
                          "\"decoding\": 4, \"odometry_noise_fraction\": -0.1"),
           "odometry_noise_fraction", "must be in [0, 1] (got -0.1)"},
          {R"([1, 2, 3])", "", "must be an object, not an array"},
          {R"({"wheel_radius_cm": 5.0, )", "", "not valid JSON"},
      });
}

TEST(RobotConfig, MissingFileAndDirectoryAreNamed) {
  EXPECT_EQ(error_of([] { (void)load_robot_config("/nonexistent/robot.json"); }),
            "/nonexistent/robot.json: no such file");
  const auto dir = test::temp_dir();
  EXPECT_EQ(error_of([&] { (void)load_robot_config(dir); }),
            dir.string() + ": is a directory, not a JSON file");
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
  EXPECT_EQ(
      error_of([&] { (void)parse_robot_config(bad.root() / "robot"); }),
      "rec/meta.json:robot.decoding: unknown quadrature decoding mode: must be 1, 2 or 4 (got 3)");
}

// --- Wheel layouts (issue 15 item 4) ------------------------------------------------------------

// Expects J (from the code) to equal the hand-worked matrix entry by entry.
void expect_jacobian(const Eigen::Matrix<double, Eigen::Dynamic, 3>& j,
                     const std::vector<std::array<double, 3>>& hand, double tol) {
  ASSERT_EQ(j.rows(), static_cast<Eigen::Index>(hand.size()));
  for (std::size_t i = 0; i < hand.size(); ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(j(static_cast<Eigen::Index>(i), c), hand[i][static_cast<std::size_t>(c)], tol)
          << "row " << i << " col " << c;
}

// Row i = [cos drive, sin drive, distance sin(drive - mount)], worked by hand for
// common/robots/three-wheel.json: wheels at 60, 180, -60 degrees, 9 cm out, each driving
// tangentially (drive = mount + 90 = 150, 270, 30): sin(90) = 1, so the rotation column is 9.
TEST(WheelLayout, ThreeWheelJacobianByHand) {
  const RobotConfig c = load_named_robot_config("three-wheel");
  EXPECT_EQ(wheel_count(c), 3);
  const double h = std::sqrt(3.0) / 2.0;
  expect_jacobian(wheel_jacobian(c), {{-h, 0.5, 9.0}, {0.0, -1.0, 9.0}, {h, 0.5, 9.0}}, 1e-12);
  // Symmetric at 120 degrees: J^T J = diag(3/2, 3/2, 3 * 81), worked by hand.
  const Eigen::Matrix3d jtj = wheel_jacobian(c).transpose() * wheel_jacobian(c);
  EXPECT_NEAR(jtj(0, 0), 1.5, 1e-12);
  EXPECT_NEAR(jtj(1, 1), 1.5, 1e-12);
  EXPECT_NEAR(jtj(2, 2), 243.0, 1e-9);
  EXPECT_NEAR(jtj(0, 1), 0.0, 1e-12);
  EXPECT_NEAR(jtj(0, 2), 0.0, 1e-12);
  EXPECT_NEAR(jtj(1, 2), 0.0, 1e-12);
  // Wheel travel: 256 lines x 4 x 19 = 19456 counts a turn of a 2.9 cm wheel.
  EXPECT_NEAR(cm_per_count(c), 2.0 * kPi * 2.9 / 19456.0, 1e-15);
  // The pseudo-inverse's fourth column (the unused counts slot) is zero, so counts[3] is ignored.
  EXPECT_EQ(wheel_pseudo_inverse(c).col(3), Eigen::Vector3d::Zero());
  EXPECT_EQ(wheel_travel_cm(c, {100, 200, 300, 12345})[3], 0.0);
}

// common/robots/four-wheel-asymmetric.json, by hand: front wheels at +-57 degrees 8.5 cm out, rear
// wheels at +-135 degrees 9.5 cm out, all tangential, wheel 3 mounted reversed (drive 135 = mount -
// 90 instead of mount + 90, so its rotation entry is 9.5 sin(270) = -9.5). cos 147 = -cos 33 =
// -0.838670567945424, sin 147 = sin 33 = 0.544639035015027 (tables), cos 225 = sin 225 =
// -0.707106781186548.
TEST(WheelLayout, AsymmetricFourWheelJacobianByHand) {
  const RobotConfig c = load_named_robot_config("four-wheel-asymmetric");
  EXPECT_EQ(wheel_count(c), 4);
  const double s2 = 0.707106781186548, c33 = 0.838670567945424, s33 = 0.544639035015027;
  expect_jacobian(wheel_jacobian(c),
                  {{-s2, -s2, 9.5}, {-c33, s33, 8.5}, {-s2, s2, -9.5}, {c33, s33, 8.5}}, 1e-14);
  // Each wheel its own travel per count: rear 500 x 4 x 19 counts per turn of 2.8 cm, front 512 x 4
  // x 24 of 2.4 cm.
  EXPECT_NEAR(cm_per_count(c, 0), 2.0 * kPi * 2.8 / 38000.0, 1e-15);
  EXPECT_NEAR(cm_per_count(c, 1), 2.0 * kPi * 2.4 / 49152.0, 1e-15);
  EXPECT_THROW((void)cm_per_count(c), std::logic_error);  // no single answer for every wheel
  EXPECT_THROW((void)counts_per_wheel_turn(c, 4), std::out_of_range);
  // The rotation column is not orthogonal to the y column here (unlike eq. (9)): by hand,
  // (-s2, s33, s2, s33) . (9.5, 8.5, -9.5, 8.5) = -19 s2 + 17 s33 = -4.176; the x column is (the
  // layout is mirror-symmetric about the x axis): (-s2, -c33, -s2, c33) . (9.5, 8.5, -9.5, 8.5) =
  // 0.
  const double y_dot_rot = -19.0 * s2 + 17.0 * s33;
  const auto j = wheel_jacobian(c);
  EXPECT_NEAR(j.col(1).dot(j.col(2)), y_dot_rot, 1e-12);
  EXPECT_NEAR(y_dot_rot, -4.1762, 1e-4);
  EXPECT_NEAR(j.col(0).dot(j.col(2)), 0.0, 1e-12);
}

// The shorthand of eq. (9) and the same robot listed wheel by wheel (mount 135, 45, -135, -45 at
// 20 cm; drive 225, 135, -45, 45) are one robot: same Jacobian as the paper's rows, same layout.
TEST(WheelLayout, ShorthandEqualsItsWheelList) {
  const RobotConfig shorthand = load_named_robot_config("default");
  const double s = std::sin(deg_to_rad(45.0)), co = std::cos(deg_to_rad(45.0));
  expect_jacobian(wheel_jacobian(shorthand),
                  {{-s, -co, 20}, {-s, co, 20}, {s, -co, 20}, {s, co, 20}}, 1e-15);
  RobotConfig listed;
  const double mounts[4] = {135, 45, -135, -45}, drives[4] = {225, 135, -45, 45};
  for (int i = 0; i < 4; ++i) listed.wheels.push_back({mounts[i], 20.0, drives[i], 5.0, 19.0, 500});
  listed.validate("listed");
  EXPECT_LT((wheel_jacobian(listed) - wheel_jacobian(shorthand)).cwiseAbs().maxCoeff(), 1e-14);
  const auto layout = wheel_layout(shorthand);
  ASSERT_EQ(layout.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(angle_diff_deg(layout[static_cast<std::size_t>(i)].mount_angle_deg, mounts[i]), 0.0,
                1e-12)
        << i;
    EXPECT_NEAR(angle_diff_deg(layout[static_cast<std::size_t>(i)].drive_angle_deg, drives[i]), 0.0,
                1e-12)
        << i;
  }
  EXPECT_NEAR(cm_per_count(listed), cm_per_count(shorthand), 1e-18);
  // The same windows give the same motion.
  const Eigen::Vector4d t = wheel_travel_cm(shorthand, {120, -340, 560, 78});
  const Eigen::Vector3d a = least_squares_motion(wheel_pseudo_inverse(shorthand), t);
  const Eigen::Vector3d b = least_squares_motion(wheel_pseudo_inverse(listed),
                                                 wheel_travel_cm(listed, {120, -340, 560, 78}));
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12);
}

// The files give each wheel every field, and a meta.json block written from a listed robot reads
// back as the same robot (decoding and wheels only: the shorthand keys do not apply).
TEST(WheelLayout, ListedRobotRoundTripsThroughTheKeyTable) {
  const RobotConfig c = load_named_robot_config("four-wheel-asymmetric");
  const config::Json block = config::write_keys(c, robot_config_keys(), config::Need::kRequired);
  std::vector<std::string> keys;
  for (auto it = block.begin(); it != block.end(); ++it) keys.push_back(it.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"decoding", "wheels"}));
  const config::Document doc = config::parse_json_text(block.dump(), "meta.json");
  RobotConfig back = parse_robot_config(doc.root());
  EXPECT_TRUE(back == c);
  // And the shorthand still writes exactly the six contract keys.
  const config::Json six =
      config::write_keys(RobotConfig{}, robot_config_keys(), config::Need::kRequired);
  EXPECT_EQ(six.size(), 6u);
  EXPECT_FALSE(six.contains("wheels"));
}

const char* kThree = R"({"decoding": 4, "wheels": [
  {"mount_angle_deg": 60, "distance_cm": 9.0, "drive_angle_deg": 150, "wheel_radius_cm": 2.9, "gear_ratio": 19, "counts_per_rev": 256},
  {"mount_angle_deg": 180, "distance_cm": 9.0, "drive_angle_deg": 270, "wheel_radius_cm": 2.9, "gear_ratio": 19, "counts_per_rev": 256},
  {"mount_angle_deg": -60, "distance_cm": 9.0, "drive_angle_deg": 30, "wheel_radius_cm": 2.9, "gear_ratio": 19, "counts_per_rev": 256}]})";

TEST(WheelLayout, BadWheelListsNameTheFileFieldAndValue) {
  const std::string v = kThree;
  const std::string w4 =
      R"(, {"mount_angle_deg": 0, "distance_cm": 9.0, "drive_angle_deg": 90, "wheel_radius_cm": 2.9, "gear_ratio": 19, "counts_per_rev": 256}]})";
  EXPECT_EQ(wheel_count(load_robot_config(test::write_file("three.json", v))), 3);
  test::expect_errors(
      [](const std::string& f) { (void)load_robot_config(f); },
      {
          // Five wheels: the board counts 3 or 4 channels.
          {test::replaced(v, "]}", w4.substr(0, w4.size() - 2) + w4), "wheels",
           "must list 3 or 4 wheels"},
          {R"({"decoding": 4, "wheels": []})", "wheels", "must list 3 or 4 wheels (got [])"},
          {R"({"decoding": 4, "wheels": [{"mount_angle_deg": 60, "distance_cm": 9.0, "drive_angle_deg": 150, "wheel_radius_cm": 2.9, "gear_ratio": 19, "counts_per_rev": 256},
              {"mount_angle_deg": 180, "distance_cm": 9.0, "drive_angle_deg": 270, "wheel_radius_cm": 2.9, "gear_ratio": 19, "counts_per_rev": 256}]})",
           "wheels", "must list 3 or 4 wheels (the board counts 3 or 4 encoder channels) (got 2)"},
          {test::replaced(v, "\"distance_cm\": 9.0, \"drive_angle_deg\": 270",
                          "\"distance_cm\": -9.0, \"drive_angle_deg\": 270"),
           "wheels[1].distance_cm", "must be >= 0 (got -9)"},
          {test::replaced(v, "\"drive_angle_deg\": 30", "\"drive_angle_deg\": 390"),
           "wheels[2].drive_angle_deg", "must be an angle within [-360, 360] degrees (got 390)"},
          {test::replaced(v, "\"wheel_radius_cm\": 2.9", "\"wheel_radius_cm\": 0"),
           "wheels[0].wheel_radius_cm", "must be > 0 (got 0)"},
          {test::replaced(v, "\"counts_per_rev\": 256}]", "\"counts_per_rev\": 0}]"),
           "wheels[2].counts_per_rev",
           "must be a positive number of encoder cycles per motor turn (got 0)"},
          {test::replaced(v, "\"gear_ratio\": 19, ", ""), "wheels[0].gear_ratio",
           "missing (required)"},
          {test::replaced(v, "\"gear_ratio\": 19, ", "\"gear\": 19, "), "wheels[0].gear",
           "unknown key (known keys: mount_angle_deg, distance_cm, drive_angle_deg, "
           "wheel_radius_cm, gear_ratio, counts_per_rev)"},
          {test::replaced(v, "\"counts_per_rev\": 256}", "\"counts_per_rev\": 256.5}"),
           "wheels[0].counts_per_rev", "must be an integer"},
          {test::replaced(v, "\"decoding\": 4, ", "\"decoding\": 4, \"wheel_radius_cm\": 2.9, "),
           "wheel_radius_cm", "not allowed beside \"wheels\": give it for each wheel"},
          {test::replaced(v, "\"decoding\": 4, ", ""), "decoding", "missing (required)"},
          {R"({"decoding": 4, "wheels": {"mount_angle_deg": 0}})", "wheels", "must be an array"},
          // Degenerate: every wheel drives along x (nothing sees y).
          {test::replaced(test::replaced(test::replaced(v, "\"drive_angle_deg\": 150",
                                                        "\"drive_angle_deg\": 0"),
                                         "\"drive_angle_deg\": 270", "\"drive_angle_deg\": 180"),
                          "\"drive_angle_deg\": 30", "\"drive_angle_deg\": 0"),
           "wheels", "degenerate wheel layout: the wheel Jacobian has rank 2, not 3"},
          // Degenerate: every wheel drives along its own radius (nothing sees a rotation).
          {test::replaced(test::replaced(test::replaced(v, "\"drive_angle_deg\": 150",
                                                        "\"drive_angle_deg\": 60"),
                                         "\"drive_angle_deg\": 270", "\"drive_angle_deg\": 180"),
                          "\"drive_angle_deg\": 30", "\"drive_angle_deg\": -60"),
           "wheels", "degenerate wheel layout: the wheel Jacobian has rank 2, not 3"},
      });
}

// Every layout the validation accepts has full column rank: a wheel list built in code is checked
// the same way (Odometry, World and SlipDetector validate their config).
TEST(WheelLayout, CodeBuiltDegenerateLayoutIsRefusedEverywhere) {
  RobotConfig c;
  for (double m : {0.0, 120.0, 240.0}) c.wheels.push_back({m, 9.0, m + 90.0, 2.9, 19.0, 256});
  EXPECT_NO_THROW(c.validate("built"));
  c.wheels[2].drive_angle_deg = c.wheels[1].drive_angle_deg =
      c.wheels[0].drive_angle_deg;  // all parallel
  EXPECT_THROW(c.validate("built"), ConfigError);
  EXPECT_THROW(Odometry{c}, ConfigError);
  c.wheels.resize(5, c.wheels[0]);
  EXPECT_NE(error_of([&] { c.validate("built"); }).find("built:wheels: must list 3 or 4 wheels"),
            std::string::npos);
}

// The board's encoder channels must match the robot's wheels (issue 15 item 4).
TEST(WheelLayout, BoardChannelsMustMatchTheWheels) {
  EXPECT_EQ(board_channel_mismatch(3, 3), std::nullopt);
  EXPECT_EQ(board_channel_mismatch(4, 4), std::nullopt);
  EXPECT_EQ(board_channel_mismatch(4, 3).value_or(""),
            "the board counts 4 encoder channels but the robot config has 3 wheels: load the "
            "bitstream built for 3 "
            "channels (make bitstream CHANNELS=3), or the robot file of this robot");
  EXPECT_NE(board_channel_mismatch(3, 4).value_or("").find(
                "the board counts 3 encoder channels but the robot config has 4"),
            std::string::npos);
  // A BoardSession on the reference board (this register map: 4 channels) refuses a three-wheel
  // robot and accepts the four-wheel one.
  sim::ReferenceBoard board;
  BoardSessionOptions o;
  o.client.response_timeout = std::chrono::milliseconds(5);
  o.wheels = wheel_count(load_named_robot_config("three-wheel"));
  const std::string err =
      error_of([&] { BoardSession s(std::make_unique<sim::UartSideTransport>(board), o); });
  EXPECT_NE(err.find("the board counts 4 encoder channels but the robot config has 3 wheels"),
            std::string::npos)
      << err;
  o.wheels = wheel_count(load_named_robot_config("four-wheel-asymmetric"));
  EXPECT_NO_THROW(BoardSession(std::make_unique<sim::UartSideTransport>(board), o));
  // A board built for three wheels (CONFIG.CHANNELS = 3) the other way round.
  sim::ReferenceBoardConfig three_cfg;
  three_cfg.channels = 3;
  sim::ReferenceBoard three(three_cfg);
  const std::string err3 =
      error_of([&] { BoardSession s(std::make_unique<sim::UartSideTransport>(three), o); });
  EXPECT_NE(err3.find("the board counts 3 encoder channels but the robot config has 4 wheels"),
            std::string::npos)
      << err3;
  o.wheels = wheel_count(load_named_robot_config("three-wheel"));
  BoardSession session(std::make_unique<sim::UartSideTransport>(three), o);
  EXPECT_EQ(session.identity().channels, 3);
}

// docs/HOWTO.md shows the three-wheel file: the snippet must be that file (one source of truth).
TEST(WheelLayout, HowtoSnippetIsTheShippedThreeWheelFile) {
  const auto file = resolve_data_file("robots", "three-wheel");
  const auto howto = file.parent_path().parent_path().parent_path() / "docs" / "HOWTO.md";
  if (!std::filesystem::exists(howto)) GTEST_SKIP() << "no docs/HOWTO.md beside " << file;
  std::ifstream in(howto);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto section = text.find("## Describe your robot");
  ASSERT_NE(section, std::string::npos);
  const auto begin = text.find("```json\n", section);
  ASSERT_NE(begin, std::string::npos);
  const auto end = text.find("```", begin + 8);
  const config::Document doc =
      config::parse_json_text(text.substr(begin + 8, end - begin - 8), howto.string());
  EXPECT_TRUE(parse_robot_config(doc.root()) == load_robot_config(file));
}

}  // namespace
}  // namespace omniloc
