#include "omniloc/robot_config.hpp"

#include <array>
#include <cmath>
#include <opencv2/core.hpp>
#include <sstream>
#include <string_view>

#include "omniloc/conventions.hpp"
#include "omniloc/data_files.hpp"

namespace omniloc {
namespace {

[[noreturn]] void fail(const std::string& source, std::string_view field, const std::string& why) {
  std::ostringstream os;
  os << source << ": field '" << field << "': " << why;
  throw ConfigError(os.str());
}

std::string number_text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void require_positive(const std::string& source, std::string_view field, double v) {
  if (!std::isfinite(v) || v <= 0.0) fail(source, field, "must be > 0 (got " + number_text(v) + ")");
}

double read_real(const cv::FileNode& n, const std::string& source, std::string_view field) {
  if (!n.isInt() && !n.isReal()) fail(source, field, "must be a number");
  return static_cast<double>(n.real());
}

int read_int(const cv::FileNode& n, const std::string& source, std::string_view field) {
  if (n.isInt()) return static_cast<int>(n);
  if (n.isReal()) {
    const double v = n.real();
    // A whole number written as 500.0 is still a count; 500.5 is not.
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 2.0e9) return static_cast<int>(v);
  }
  fail(source, field, "must be an integer");
}

struct RealField {
  std::string_view name;
  double RobotConfig::*member;
  bool required;
};

constexpr std::array<RealField, 11> kRealFields{{
    {"wheel_radius_cm", &RobotConfig::wheel_radius_cm, true},
    {"center_to_wheel_cm", &RobotConfig::center_to_wheel_cm, true},
    {"motor_angle_deg", &RobotConfig::motor_angle_deg, true},
    {"gear_ratio", &RobotConfig::gear_ratio, true},
    {"window_period_ms", &RobotConfig::window_period_ms, false},
    {"clock_hz", &RobotConfig::clock_hz, false},
    {"slip_threshold_cm_per_s", &RobotConfig::slip_threshold_cm_per_s, false},
    {"wheel_noise_cm_per_sqrt_cm", &RobotConfig::wheel_noise_cm_per_sqrt_cm, false},
    {"max_accel_cm_per_s2", &RobotConfig::max_accel_cm_per_s2, false},
    {"odometry_noise_fraction", &RobotConfig::odometry_noise_fraction, false},
    {"gyro_arw_deg_per_sqrt_s", &RobotConfig::gyro_arw_deg_per_sqrt_s, false},
}};

struct IntField {
  std::string_view name;
  int RobotConfig::*member;
};

constexpr std::array<IntField, 2> kIntFields{{
    {"counts_per_rev", &RobotConfig::counts_per_rev},
    {"decoding", &RobotConfig::decoding},
}};

std::string known_fields() {
  std::string s;
  for (const auto& f : kRealFields) s += std::string(s.empty() ? "" : ", ") + std::string(f.name);
  for (const auto& f : kIntFields) s += ", " + std::string(f.name);
  return s;
}

}  // namespace

double counts_per_wheel_turn(const RobotConfig& c) {
  return static_cast<double>(c.counts_per_rev) * c.decoding * c.gear_ratio;
}

double cm_per_count(const RobotConfig& c) {
  return 2.0 * kPi * c.wheel_radius_cm / counts_per_wheel_turn(c);
}

void validate_robot_config(const RobotConfig& c, const std::string& source) {
  require_positive(source, "wheel_radius_cm", c.wheel_radius_cm);
  require_positive(source, "center_to_wheel_cm", c.center_to_wheel_cm);
  // Equation (9) needs both sin and cos of theta_m non-zero, or the 4x3 matrix loses rank.
  if (!std::isfinite(c.motor_angle_deg) || c.motor_angle_deg <= 0.0 || c.motor_angle_deg >= 90.0)
    fail(source, "motor_angle_deg",
         "must be strictly between 0 and 90 degrees, or equation (9) loses rank (got " +
             number_text(c.motor_angle_deg) + ")");
  require_positive(source, "gear_ratio", c.gear_ratio);
  if (c.counts_per_rev <= 0)
    fail(source, "counts_per_rev",
         "must be a positive number of encoder cycles per motor turn (got " +
             std::to_string(c.counts_per_rev) + ")");
  if (c.decoding != 1 && c.decoding != 2 && c.decoding != 4)
    fail(source, "decoding",
         "unknown quadrature decoding mode: must be 1, 2 or 4 (got " + std::to_string(c.decoding) + ")");
  require_positive(source, "window_period_ms", c.window_period_ms);
  require_positive(source, "clock_hz", c.clock_hz);
  require_positive(source, "slip_threshold_cm_per_s", c.slip_threshold_cm_per_s);
  require_positive(source, "max_accel_cm_per_s2", c.max_accel_cm_per_s2);
  if (!std::isfinite(c.odometry_noise_fraction) || c.odometry_noise_fraction < 0.0)
    fail(source, "odometry_noise_fraction", "must be >= 0 (got " + number_text(c.odometry_noise_fraction) + ")");
  if (!std::isfinite(c.wheel_noise_cm_per_sqrt_cm) || c.wheel_noise_cm_per_sqrt_cm < 0.0)
    fail(source, "wheel_noise_cm_per_sqrt_cm", "must be >= 0 (got " + number_text(c.wheel_noise_cm_per_sqrt_cm) + ")");
  if (!std::isfinite(c.gyro_arw_deg_per_sqrt_s) || c.gyro_arw_deg_per_sqrt_s < 0.0)
    fail(source, "gyro_arw_deg_per_sqrt_s", "must be >= 0 (got " + number_text(c.gyro_arw_deg_per_sqrt_s) + ")");
}

RobotConfig parse_robot_config(const cv::FileNode& node, const std::string& source) {
  if (node.empty() || !node.isMap()) throw ConfigError(source + ": expected a JSON object with the robot fields");
  RobotConfig c;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = (*it).name();
    bool known = false;
    for (const auto& f : kRealFields) known = known || key == f.name;
    for (const auto& f : kIntFields) known = known || key == f.name;
    if (!known) fail(source, key, "unknown field (known fields: " + known_fields() + ")");
  }
  for (const auto& f : kRealFields) {
    const cv::FileNode n = node[std::string(f.name)];
    if (n.empty()) {
      if (f.required) fail(source, f.name, "missing (required)");
      continue;
    }
    c.*f.member = read_real(n, source, f.name);
  }
  for (const auto& f : kIntFields) {
    const cv::FileNode n = node[std::string(f.name)];
    if (n.empty()) fail(source, f.name, "missing (required)");
    c.*f.member = read_int(n, source, f.name);
  }
  validate_robot_config(c, source);
  return c;
}

RobotConfig load_robot_config(const std::filesystem::path& path) {
  const std::string source = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw ConfigError(source + ": no such file");
  cv::FileStorage fs;
  try {
    if (!fs.open(source, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON))
      throw ConfigError(source + ": cannot be opened as JSON");
  } catch (const cv::Exception& e) {
    throw ConfigError(source + ": not a valid JSON object (" + e.err + ")");
  }
  return parse_robot_config(fs.root(), source);
}

RobotConfig load_named_robot_config(const std::string& name_or_path) {
  return load_robot_config(resolve_data_file("robots", name_or_path));
}

}  // namespace omniloc
