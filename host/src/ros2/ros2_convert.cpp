// The ROS 2 conventions as plain functions (no DDS here): topic names, quaternions, covariances
// and time stamps.
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "omniloc/ros2_bridge.hpp"

namespace omniloc::ros2 {

std::string dds_topic_name(const std::string& ros_topic) {
  const auto bad = [&](const std::string& why) {
    return std::invalid_argument("ROS 2 topic '" + ros_topic + "': " + why);
  };
  if (ros_topic.empty() || ros_topic[0] != '/')
    throw bad("must be an absolute name starting with '/'");
  if (ros_topic.size() == 1 || ros_topic.back() == '/') throw bad("must not end with '/'");
  bool token_start = true;
  for (std::size_t i = 1; i < ros_topic.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(ros_topic[i]);
    if (c == '/') {
      if (token_start) throw bad("empty token ('//')");
      token_start = true;
      continue;
    }
    if (!(std::isalnum(c) || c == '_')) throw bad("only letters, digits, '_' and '/' are allowed");
    if (token_start && std::isdigit(c)) throw bad("a token must not start with a digit");
    token_start = false;
  }
  return "rt" + ros_topic;
}

QuaternionZ yaw_quaternion(double yaw_deg) {
  const double half = deg_to_rad(yaw_deg) / 2.0;
  return {std::sin(half), std::cos(half)};
}

std::optional<double> quaternion_yaw_deg(double x, double y, double z, double w) {
  const double n2 = x * x + y * y + z * z + w * w;
  if (!std::isfinite(n2) || n2 <= 0.0) return std::nullopt;
  // The image of +x under the rotation (the first column of the rotation matrix, unnormalised by
  // n2, which does not change its direction).
  const double rx = w * w + x * x - y * y - z * z;
  const double ry = 2.0 * (x * y + w * z);
  if (rx == 0.0 && ry == 0.0) return std::nullopt;  // +x turned straight up or down: no heading
  return wrap_deg(rad_to_deg(std::atan2(ry, rx)));
}

std::array<double, 36> planar_covariance(double sigma_xy_cm, double sigma_yaw_deg) {
  std::array<double, 36> c{};
  const double s_m = sigma_xy_cm / 100.0;  // radial: each axis carries half its square
  const double s_rad = deg_to_rad(sigma_yaw_deg);
  c[0 * 6 + 0] = s_m * s_m / 2.0;
  c[1 * 6 + 1] = s_m * s_m / 2.0;
  c[5 * 6 + 5] = s_rad * s_rad;
  return c;
}

RosTime ros_time_from_ms(double unix_ms) {
  const double sec = std::floor(unix_ms / 1000.0);
  double nanos = std::round((unix_ms - sec * 1000.0) * 1e6);
  double s = sec;
  if (nanos >= 1e9) {
    nanos -= 1e9;
    s += 1.0;
  }
  return {static_cast<std::int32_t>(s), static_cast<std::uint32_t>(nanos)};
}

}  // namespace omniloc::ros2
