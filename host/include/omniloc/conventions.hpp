// Units and coordinate conventions, fixed once for the whole project (docs/ARCHITECTURE.md).
//
// Field frame: centimetres, origin at the corner of the outer border area, +x along the long
// (750 cm) side, +y along the short (550 cm) side; the FIRA field centre is (375, 275).
// Robot frame: +x forward, +y to the left. Angles: degrees, counter-clockwise from +x.
// Wheels: numbered 1..4 (index 0..3 in code) with the signs of equation (9) of the paper.
#pragma once

#include <Eigen/Core>

namespace omniloc {

inline constexpr double kPi = 3.14159265358979323846;

[[nodiscard]] constexpr double deg_to_rad(double deg) { return deg * kPi / 180.0; }
[[nodiscard]] constexpr double rad_to_deg(double rad) { return rad * 180.0 / kPi; }

/// Wraps an angle into (-180, 180] degrees.
[[nodiscard]] double wrap_deg(double angle_deg);

/// Signed smallest difference a - b, in (-180, 180] degrees.
[[nodiscard]] double angle_diff_deg(double a_deg, double b_deg);

/// A robot pose in the field frame.
struct Pose2 {
  double x_cm = 0.0;
  double y_cm = 0.0;
  double yaw_deg = 0.0;
};

/// Rotates a robot-frame vector into the field frame for a robot heading yaw_deg.
[[nodiscard]] Eigen::Vector2d robot_to_field(const Eigen::Vector2d& v_robot, double yaw_deg);

/// Rotates a field-frame vector into the robot frame for a robot heading yaw_deg.
[[nodiscard]] Eigen::Vector2d field_to_robot(const Eigen::Vector2d& v_field, double yaw_deg);

/// Equation (9) of the paper: wheel speeds V = J * [Vx, Vy, omega_R] with Vx, Vy in the robot
/// frame (cm/s) and omega_R in rad/s; row i is wheel i+1:
///   [-sin(tm) -cos(tm) R; -sin(tm) cos(tm) R; sin(tm) -cos(tm) R; sin(tm) cos(tm) R].
[[nodiscard]] Eigen::Matrix<double, 4, 3> wheel_jacobian(double motor_angle_deg,
                                                         double center_to_wheel_cm);

}  // namespace omniloc
