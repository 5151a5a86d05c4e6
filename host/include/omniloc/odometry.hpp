// Encoder + gyroscope odometry (paper section 2.4, equations (10)-(15)), in two variants:
//
//  * PaperOdometry: equations (10)-(15) exactly as printed, kept to show what they do. Equation (13)
//    gives every wheel the same signs, so for any pure translation the four terms cancel
//    (sum of eq. (9)'s first two columns is zero) and only rotation is "seen"; equation (11) uses
//    R/2 where the arc of a wheel on radius R is R * angle. docs/ODOMETRY.md measures the result.
//  * Odometry: least squares through the pseudo-inverse of eq. (9)'s 4x3 matrix, heading from the
//    gyroscope (wheel rotation kept as a cross-check), field-frame integration at the mid-window
//    heading, time from window timestamps, slip detection and isolation from the LS residual with
//    down-weighting, origin reset, and a per-pose uncertainty.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "omniloc/conventions.hpp"
#include "omniloc/robot_config.hpp"

namespace omniloc {

/// One board window, as in a recording's encoders.csv row (t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg).
struct EncoderWindow {
  std::uint32_t seq = 0;
  double t_end_ms = 0.0;                 ///< end of the window (board time)
  std::array<std::int32_t, 4> counts{};  ///< wheel 1..4 counts in this window (eq. (9) signs)
  double gyro_yaw_deg = 0.0;             ///< gyro's integrated yaw, field frame, at t_end_ms
};

/// Per-wheel slip finding for one window.
struct SlipReport {
  bool detected = false;
  int wheel = 0;                  ///< 1..4 when detected, else 0
  double magnitude_cm = 0.0;      ///< wheel travel not explained by the robot's motion (signed)
  double magnitude_cm_per_s = 0.0;
  double residual_cm_per_s = 0.0; ///< norm of the 4-wheel LS residual (gyro heading), per second
  double threshold_cm_per_s = 0.0;  ///< what the residual was compared with in this window
};

struct OdometryEstimate {
  double t_ms = 0.0;
  Pose2 pose;
  double sigma_xy_cm = 0.0;       ///< 1-sigma position uncertainty (isotropic)
  double sigma_yaw_deg = 0.0;
  double speed_cm_per_s = 0.0;    ///< over the last window
  double yaw_rate_deg_per_s = 0.0;
  double distance_cm = 0.0;       ///< path length since the last origin reset
  double wheel_yaw_deg = 0.0;     ///< heading integrated from the wheels alone (cross-check)
  SlipReport slip;
};

/// Least-squares estimate of one window's motion from four wheel travels (cm):
/// body-frame displacement dx, dy (cm) and rotation (rad), all from eq. (9)'s pseudo-inverse.
[[nodiscard]] Eigen::Vector3d least_squares_motion(const Eigen::Matrix<double, 3, 4>& pinv,
                                                   const Eigen::Vector4d& wheel_travel_cm);

/// The pseudo-inverse (J^T J)^-1 J^T of eq. (9)'s matrix for this robot.
[[nodiscard]] Eigen::Matrix<double, 3, 4> wheel_pseudo_inverse(const RobotConfig& config);

/// Wheel travel in cm for a window's counts.
[[nodiscard]] Eigen::Vector4d wheel_travel_cm(const RobotConfig& config,
                                              const std::array<std::int32_t, 4>& counts);

class Odometry {
 public:
  explicit Odometry(const RobotConfig& config);

  /// Origin reset: the pose at the end of the last window processed is `pose` (the integration
  /// algorithm does this every 125 ms). The gyro heading is re-anchored so yaw follows `pose`.
  /// Before the first window the gyro is taken as aligned with the field (issue 7 contract).
  void reset(const Pose2& pose, double sigma_xy_cm = 0.0, double sigma_yaw_deg = 0.0);

  /// Integrates one window. Throws std::invalid_argument (naming seq and times) if the window's
  /// time does not advance or a value is not finite.
  const OdometryEstimate& update(const EncoderWindow& window);

  [[nodiscard]] const OdometryEstimate& estimate() const { return est_; }
  [[nodiscard]] const RobotConfig& config() const { return config_; }

 private:
  RobotConfig config_;
  Eigen::Matrix<double, 4, 3> jacobian_;
  Eigen::Matrix<double, 3, 4> pinv_;
  double cm_per_count_;
  OdometryEstimate est_;
  bool have_window_ = false;
  double last_t_ms_ = 0.0;
  double last_gyro_deg_ = 0.0;
  double yaw_offset_deg_ = 0.0;             // pose yaw = gyro yaw + offset
  Eigen::Vector2d last_velocity_field_{0.0, 0.0};  // cm/s, for the motion prior
};

/// How eq. (14)'s theta_g is read: the printed text defines theta_g as the yaw *difference*
/// (eq. (11)), which cannot give a field-frame direction; the only workable reading uses the
/// gyro's yaw. Both are offered so the difference can be measured.
enum class PaperHeading { kGyroYaw, kGyroDifference };

class PaperOdometry {
 public:
  explicit PaperOdometry(const RobotConfig& config, PaperHeading heading = PaperHeading::kGyroYaw);
  void reset(const Pose2& pose);
  const OdometryEstimate& update(const EncoderWindow& window);
  [[nodiscard]] const OdometryEstimate& estimate() const { return est_; }

 private:
  RobotConfig config_;
  PaperHeading heading_;
  OdometryEstimate est_;
  bool have_window_ = false;
  double last_gyro_deg_ = 0.0;
  double yaw_offset_deg_ = 0.0;
};

}  // namespace omniloc
