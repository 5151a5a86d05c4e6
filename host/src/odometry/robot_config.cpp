#include "omniloc/robot_config.hpp"

#include <cmath>

#include "omniloc/config_reader.hpp"
#include "omniloc/conventions.hpp"

namespace omniloc {

using config::Need;

const config::KeyTable<RobotConfig>& robot_config_keys() {
  using config::key;
  static const config::KeyTable<RobotConfig> table = {
      // --- required: the recording contract's robot block ---
      key("wheel_radius_cm", &RobotConfig::wheel_radius_cm, Need::kRequired),
      key("center_to_wheel_cm", &RobotConfig::center_to_wheel_cm, Need::kRequired),
      key("motor_angle_deg", &RobotConfig::motor_angle_deg, Need::kRequired),
      key("gear_ratio", &RobotConfig::gear_ratio, Need::kRequired),
      key("counts_per_rev", &RobotConfig::counts_per_rev, Need::kRequired),
      key("decoding", &RobotConfig::decoding, Need::kRequired),
      // --- optional ---
      key("window_period_ms", &RobotConfig::window_period_ms),
      key("clock_hz", &RobotConfig::clock_hz),
      key("slip_threshold_cm_per_s", &RobotConfig::slip_threshold_cm_per_s),
      key("wheel_noise_cm_per_sqrt_cm", &RobotConfig::wheel_noise_cm_per_sqrt_cm),
      key("max_accel_cm_per_s2", &RobotConfig::max_accel_cm_per_s2),
      key("odometry_noise_fraction", &RobotConfig::odometry_noise_fraction),
      key("gyro_arw_deg_per_sqrt_s", &RobotConfig::gyro_arw_deg_per_sqrt_s),
  };
  return table;
}

double counts_per_wheel_turn(const RobotConfig& c) {
  return static_cast<double>(c.counts_per_rev) * c.decoding * c.gear_ratio;
}

double cm_per_count(const RobotConfig& c) {
  return 2.0 * kPi * c.wheel_radius_cm / counts_per_wheel_turn(c);
}

void RobotConfig::validate(const config::Origin& at) const {
  using config::require;
  const auto positive = [&](double v, const char* field) {
    require(std::isfinite(v) && v > 0.0, at / field, "must be > 0", v);
  };
  const auto non_negative = [&](double v, const char* field) {
    require(std::isfinite(v) && v >= 0.0, at / field, "must be >= 0", v);
  };
  positive(wheel_radius_cm, "wheel_radius_cm");
  positive(center_to_wheel_cm, "center_to_wheel_cm");
  // Equation (9) needs both sin and cos of theta_m non-zero, or the 4x3 matrix loses rank.
  require(std::isfinite(motor_angle_deg) && motor_angle_deg > 0.0 && motor_angle_deg < 90.0, at / "motor_angle_deg",
          "must be strictly between 0 and 90 degrees, or equation (9) loses rank", motor_angle_deg);
  positive(gear_ratio, "gear_ratio");
  require(counts_per_rev > 0, at / "counts_per_rev", "must be a positive number of encoder cycles per motor turn",
          counts_per_rev);
  require(decoding == 1 || decoding == 2 || decoding == 4, at / "decoding",
          "unknown quadrature decoding mode: must be 1, 2 or 4", decoding);
  positive(window_period_ms, "window_period_ms");
  positive(clock_hz, "clock_hz");
  positive(slip_threshold_cm_per_s, "slip_threshold_cm_per_s");
  non_negative(wheel_noise_cm_per_sqrt_cm, "wheel_noise_cm_per_sqrt_cm");
  positive(max_accel_cm_per_s2, "max_accel_cm_per_s2");
  non_negative(odometry_noise_fraction, "odometry_noise_fraction");
  non_negative(gyro_arw_deg_per_sqrt_s, "gyro_arw_deg_per_sqrt_s");
}

void validate_robot_config(const RobotConfig& c, const std::string& source) { c.validate(source); }

RobotConfig parse_robot_config(const config::Node& node) {
  RobotConfig c;
  config::read_keys(node, robot_config_keys(), c);
  c.validate(node.origin());
  return c;
}

RobotConfig load_robot_config(const std::filesystem::path& path) {
  return parse_robot_config(config::parse_json_file(path).root());
}

RobotConfig load_named_robot_config(const std::string& name_or_path) {
  return load_robot_config(resolve_data_file("robots", name_or_path));
}

}  // namespace omniloc
