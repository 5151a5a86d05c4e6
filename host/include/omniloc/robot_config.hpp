// Robot geometry and encoder settings (paper section 2.3, equation (9)), read from a JSON file.
//
// A robot has 3 or 4 omni wheels, given in one of two forms:
//  * the symmetric shorthand of equation (9) (the recording contract of issue 7): wheel_radius_cm,
//    center_to_wheel_cm, motor_angle_deg, gear_ratio, counts_per_rev for four identical wheels in
//    the paper's layout;
//  * "wheels": a list of 3 or 4 wheels, each with its mount angle, distance from the centre, drive
//    direction, wheel radius, gear ratio and encoder resolution (any layout whose Jacobian has
//    full column rank 3).
// decoding is required in both forms. Optional keys (with the defaults below) tune the window
// timing and the odometry; any other key is refused, so that a misspelt optional key cannot
// silently fall back to its default. Format and chosen values: docs/ODOMETRY.md. Default file:
// common/robots/default.json (the shorthand).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "omniloc/config.hpp"  // ConfigError

namespace omniloc {

inline constexpr int kMinWheels = 3;
inline constexpr int kMaxWheels = 4;  ///< EncoderWindow::counts has this many slots

/// One omni wheel, in the robot frame (+x forward, +y left, angles counter-clockwise from +x).
/// Its encoder measures the speed of the robot's point under the wheel along the drive direction:
/// V = u . (v + omega x p), p = distance (cos mount, sin mount), u = (cos drive, sin drive).
struct WheelConfig {
  /// where the wheel sits: direction of its contact point from the centre
  double mount_angle_deg = 0.0;
  double distance_cm = 0.0;  ///< centre to contact point
  /// direction the contact point moves for a positive count (tangential
  /// wheels: mount + 90 turning the robot counter-clockwise, mount - 90 reversed)
  double drive_angle_deg = 90.0;
  double wheel_radius_cm = 5.0;
  double gear_ratio = 19.0;  ///< motor turns per wheel turn
  int counts_per_rev = 500;  ///< encoder cycles (lines) per motor turn
  bool operator==(const WheelConfig&) const = default;
};

/// The member initialisers are the shipped defaults: a test checks they equal every key of
/// common/robots/default.json.
struct RobotConfig {
  // --- required (recording contract) ---
  double wheel_radius_cm = 5.0;      ///< r of equation (7)
  double center_to_wheel_cm = 20.0;  ///< R of equation (9)
  double motor_angle_deg = 45.0;     ///< theta_m of equation (9)
  double gear_ratio = 19.0;          ///< N of equation (10): motor turns per wheel turn
  int counts_per_rev = 500;          ///< encoder cycles (lines) per motor turn
  int decoding = 4;                  ///< quadrature decoding multiplier: 1, 2 or 4

  /// The wheels one by one; empty = the symmetric shorthand above (four wheels of eq. (9)). When
  /// given, the five shorthand geometry members above are not used (and not read or written).
  std::vector<WheelConfig> wheels;

  // --- optional ---
  /// LS residual rate above which a wheel is called slipping
  double slip_threshold_cm_per_s = 5.0;
  /// random wheel travel noise; the threshold is at least 6 sigma
  double wheel_noise_cm_per_sqrt_cm = 0.01;
  double max_accel_cm_per_s2 = 400.0;      ///< motion prior used to tell diagonal wheels apart
  double odometry_noise_fraction = 0.005;  ///< 1-sigma position uncertainty growth per cm driven
  double gyro_arw_deg_per_sqrt_s = 0.01;   ///< gyro angle random walk, for yaw uncertainty
  /// The fastest the robot can turn (deg/s): a window's gyro yaw that changes by more than this
  /// times the window's span is a fault and dropped (GyroYawGuard, odometry.hpp). 1500 deg/s
  /// (over four turns a second) is beyond any wheeled soccer robot and below the board gyro's
  /// +-2000 deg/s full scale.
  double max_yaw_rate_deg_per_s = 1500.0;

  /// Throws ConfigError "<at>.<field>: <why> (got <value>)" for the first bad field.
  void validate(const config::Origin& at) const;
  bool operator==(const RobotConfig&) const = default;
};

/// Number of wheels: wheels.size(), or 4 for the shorthand.
[[nodiscard]] int wheel_count(const RobotConfig& config);

/// The wheels one by one (the shorthand expanded: wheel 1 back-left, 2 front-left, 3 back-right,
/// 4 front-right, with the rows of eq. (9)).
[[nodiscard]] std::vector<WheelConfig> wheel_layout(const RobotConfig& config);

/// Wheel i's contact point in the robot frame (cm), i = 0..wheel_count-1.
[[nodiscard]] std::vector<Eigen::Vector2d> wheel_positions_cm(const RobotConfig& config);

/// The wheel Jacobian J (wheel_count x 3): wheel travels (cm) = J [dx_cm, dy_cm, dtheta_rad] for a
/// body-frame motion; row i = [cos drive, sin drive, distance sin(drive - mount)]. For the
/// shorthand it is eq. (9)'s matrix (wheel_jacobian(motor_angle_deg, center_to_wheel_cm)).
[[nodiscard]] Eigen::Matrix<double, Eigen::Dynamic, 3> wheel_jacobian(const RobotConfig& config);

/// Encoder counts per turn of wheel i (0-based): counts_per_rev x decoding x gear_ratio.
[[nodiscard]] double counts_per_wheel_turn(const RobotConfig& config, int wheel);
/// Wheel i's travel per count, in cm.
[[nodiscard]] double cm_per_count(const RobotConfig& config, int wheel);

/// The same for a robot whose wheels all share one value (the shorthand always does); throws
/// std::logic_error when they differ, rather than answer for one wheel.
[[nodiscard]] double counts_per_wheel_turn(const RobotConfig& config);
[[nodiscard]] double cm_per_count(const RobotConfig& config);

/// Why a board with `board_channels` encoder channels cannot serve a robot with `robot_wheels`
/// wheels (wheel_count), or nullopt when it can (the numbers are equal).
[[nodiscard]] std::optional<std::string> board_channel_mismatch(int board_channels,
                                                                int robot_wheels);

/// config.validate(source).
void validate_robot_config(const RobotConfig& config, const std::string& source);

/// Reads and validates a robot block from a parsed JSON node (a robot file's root or meta.json's
/// "robot"); errors name the node's origin ("rec/meta.json:robot.decoding").
[[nodiscard]] RobotConfig parse_robot_config(const config::Node& node);

/// The key table (config_reader.hpp) that writes a robot block: the six contract keys and "wheels"
/// are Need::kRequired (meta.json writes those that apply: the shorthand's five geometry keys, or
/// "wheels", and decoding), the others optional. parse_robot_config() reads with it, the shorthand
/// keys being required exactly when "wheels" is absent.
[[nodiscard]] const std::vector<config::Key<RobotConfig>>& robot_config_keys();

/// Reads and validates a JSON file whose top level is the robot block.
[[nodiscard]] RobotConfig load_robot_config(const std::filesystem::path& path);

/// Loads common/robots/<name>.json (or `name` itself if it is a path), located like the other
/// shared data files (resolve_data_file, config.hpp).
[[nodiscard]] RobotConfig load_named_robot_config(const std::string& name_or_path);

}  // namespace omniloc
