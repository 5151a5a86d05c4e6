// Equations (10)-(15) of the paper, literally. Its defects are kept on purpose (see odometry.hpp);
// the only liberty taken is skipping a window whose eq. (14) length is zero, where
// atan(0/0) is undefined and the term contributes nothing anyway.
#include <cmath>
#include <stdexcept>
#include <string>

#include "omniloc/odometry.hpp"
#include "omniloc/regmap.hpp"

namespace omniloc {

PaperOdometry::PaperOdometry(const RobotConfig& config, PaperHeading heading)
    : config_(config), heading_(heading) {
  validate_robot_config(config, "PaperOdometry config");
  if (!config.wheels.empty())
    throw std::invalid_argument(
        "PaperOdometry: equations (10)-(15) are written for the paper's symmetric four-wheel "
        "layout "
        "(motor_angle_deg, center_to_wheel_cm); this robot lists its " +
        std::to_string(config.wheels.size()) + " wheels one by one: use Odometry");
}

void PaperOdometry::reset(const Pose2& pose) {
  if (!have_window_) last_gyro_deg_ = pose.yaw_deg;
  yaw_offset_deg_ = angle_diff_deg(pose.yaw_deg, last_gyro_deg_);
  est_.pose = {pose.x_cm, pose.y_cm, wrap_deg(pose.yaw_deg)};
  est_.distance_cm = 0.0;
}

const OdometryEstimate& PaperOdometry::update(const EncoderWindow& window) {
  // The paper's FPGA has a fixed sample period T; eq. (10) divides by res x 0.01 (T = 10 ms, the
  // board's window period).
  const double t_s = regmap::kWindowPeriodMs / 1000.0;
  const double res = static_cast<double>(config_.counts_per_rev) * config_.decoding;
  const double n = config_.gear_ratio;
  const double r = config_.wheel_radius_cm;
  const double big_r = config_.center_to_wheel_cm;
  const double tm = deg_to_rad(config_.motor_angle_deg);

  const double theta_g_deg = angle_diff_deg(window.gyro_yaw_deg, last_gyro_deg_);  // (11)
  const double d = theta_g_deg * kPi / 180.0 * big_r / 2.0;                        // (11)
  double sx = 0.0;
  double sy = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double di = (1.0 / n) * (window.counts[static_cast<std::size_t>(i)] / (res * 0.01)) *
                      (2.0 * kPi * r * t_s);  // (10)
    const double si = di - d;                 // (12)
    sx += -std::cos(tm) * si;                 // (13)
    sy += -std::sin(tm) * si;                 // (13)
  }
  sx *= 0.5;  // (14)
  sy *= 0.5;  // (14)
  const double length = std::sqrt(sx * sx + sy * sy);
  const double yaw_deg = wrap_deg(window.gyro_yaw_deg + yaw_offset_deg_);
  const double theta_g_term = heading_ == PaperHeading::kGyroYaw ? yaw_deg : theta_g_deg;
  if (length > 0.0) {
    const double theta_e = std::atan(sy / sx) + deg_to_rad(theta_g_term);      // (14)
    est_.pose = est_.pose.shifted(length * Eigen::Vector2d(std::cos(theta_e),  // (15)
                                                           std::sin(theta_e)));
  }
  est_.t_ms = window.t_end_ms;
  est_.pose.yaw_deg = yaw_deg;
  est_.distance_cm += length;
  est_.speed_cm_per_s = length / t_s;
  last_gyro_deg_ = window.gyro_yaw_deg;
  have_window_ = true;
  return est_;
}

}  // namespace omniloc
