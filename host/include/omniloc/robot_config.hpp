// Robot geometry and encoder settings (paper section 2.3, equation (9)), read from a JSON file.
//
// The required keys are exactly the "robot" block of the recording contract (issue 7):
// wheel_radius_cm, center_to_wheel_cm, motor_angle_deg, gear_ratio, counts_per_rev, decoding.
// Optional keys (with the defaults below) tune the window timing and the odometry; any other key
// is refused, so that a misspelt optional key cannot silently fall back to its default.
// Format and chosen values: docs/ODOMETRY.md. Default file: common/robots/default.json.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "omniloc/config.hpp"  // ConfigError

namespace omniloc {

/// The member initialisers are the shipped defaults: a test checks they equal every key of
/// common/robots/default.json.
struct RobotConfig {
  // --- required (recording contract) ---
  double wheel_radius_cm = 5.0;     ///< r of equation (7)
  double center_to_wheel_cm = 20.0; ///< R of equation (9)
  double motor_angle_deg = 45.0;    ///< theta_m of equation (9)
  double gear_ratio = 19.0;         ///< N of equation (10): motor turns per wheel turn
  int counts_per_rev = 500;         ///< encoder cycles (lines) per motor turn
  int decoding = 4;                 ///< quadrature decoding multiplier: 1, 2 or 4

  // --- optional ---
  double window_period_ms = 10.0;   ///< nominal board window (100 Hz); odometry uses timestamps
  double clock_hz = 40.0e6;         ///< board clock (timestamps count its cycles)
  double slip_threshold_cm_per_s = 5.0;  ///< LS residual rate above which a wheel is called slipping
  double wheel_noise_cm_per_sqrt_cm = 0.01;  ///< random wheel travel noise; the threshold is at least 6 sigma
  double max_accel_cm_per_s2 = 400.0;    ///< motion prior used to tell diagonal wheels apart
  double odometry_noise_fraction = 0.005;  ///< 1-sigma position uncertainty growth per cm driven
  double gyro_arw_deg_per_sqrt_s = 0.01;   ///< gyro angle random walk, for yaw uncertainty

  /// Throws ConfigError "<at>.<field>: <why> (got <value>)" for the first bad field.
  void validate(const config::Origin& at) const;
  bool operator==(const RobotConfig&) const = default;
};

/// Encoder counts per wheel turn: counts_per_rev x decoding x gear_ratio (issue 7 contract).
[[nodiscard]] double counts_per_wheel_turn(const RobotConfig& config);

/// Wheel travel per count, in cm.
[[nodiscard]] double cm_per_count(const RobotConfig& config);

/// config.validate(source).
void validate_robot_config(const RobotConfig& config, const std::string& source);

/// Reads and validates a robot block from a parsed JSON node (a robot file's root or meta.json's
/// "robot"); errors name the node's origin ("rec/meta.json:robot.decoding").
[[nodiscard]] RobotConfig parse_robot_config(const config::Node& node);

/// The key table (config_reader.hpp) that reads and writes a robot block: the six contract keys
/// are Need::kRequired (meta.json writes only those), the others optional.
[[nodiscard]] const std::vector<config::Key<RobotConfig>>& robot_config_keys();

/// Reads and validates a JSON file whose top level is the robot block.
[[nodiscard]] RobotConfig load_robot_config(const std::filesystem::path& path);

/// Loads common/robots/<name>.json (or `name` itself if it is a path), located like the other
/// shared data files (resolve_data_file, data_files.hpp).
[[nodiscard]] RobotConfig load_named_robot_config(const std::string& name_or_path);

}  // namespace omniloc
