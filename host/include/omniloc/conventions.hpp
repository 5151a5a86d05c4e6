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

[[nodiscard]] constexpr double deg_to_rad(double deg) {
  return deg * kPi / 180.0;
}
[[nodiscard]] constexpr double rad_to_deg(double rad) {
  return rad * 180.0 / kPi;
}

/// Wraps an angle into (-180, 180] degrees.
[[nodiscard]] double wrap_deg(double angle_deg);

/// Signed smallest difference a - b, in (-180, 180] degrees.
[[nodiscard]] double angle_diff_deg(double a_deg, double b_deg);

/// The angle a fraction f of the way from a to b along the shorter arc, wrapped into (-180, 180].
[[nodiscard]] double interpolate_deg(double a_deg, double b_deg, double f);

/// A rigid 2-D pose: a position and a heading, in the field frame unless said otherwise. A value
/// type with the algebra of SE(2), in the manner of B-Human's Pose2f: `a * b` is b expressed in
/// a's frame carried into a's parent frame (compose), `a.inverse()` undoes a, `a * p` maps a point
/// given in a's frame. Yaw is kept wrapped into (-180, 180] by every operation here.
struct Pose2 {
  double x_cm = 0.0;
  double y_cm = 0.0;
  double yaw_deg = 0.0;

  [[nodiscard]] Eigen::Vector2d position_cm() const { return {x_cm, y_cm}; }
  /// Compose: this pose, then `local` expressed in this pose's frame.
  [[nodiscard]] Pose2 operator*(const Pose2& local) const;
  Pose2& operator*=(const Pose2& local) { return *this = *this * local; }
  /// A point given in this pose's frame, in the parent frame.
  [[nodiscard]] Eigen::Vector2d operator*(const Eigen::Vector2d& p_local_cm) const;
  /// The pose that undoes this one: p * p.inverse() and p.inverse() * p are the identity.
  [[nodiscard]] Pose2 inverse() const;
  /// Moved by a displacement given in the parent (field) frame, the heading kept: a field-frame
  /// shift, where `*` would move along this pose's own axes. The yaw is left as it is.
  [[nodiscard]] Pose2 shifted(const Eigen::Vector2d& d_parent_cm) const {
    return {x_cm + d_parent_cm.x(), y_cm + d_parent_cm.y(), yaw_deg};
  }
  /// The same position with the heading yaw_deg (wrapped).
  [[nodiscard]] Pose2 with_yaw(double new_yaw_deg) const;
  friend bool operator==(const Pose2&, const Pose2&) = default;
};

/// a * b (see Pose2::operator*).
[[nodiscard]] inline Pose2 compose(const Pose2& a, const Pose2& b) {
  return a * b;
}

/// The pose a fraction f of the way from a to b: the position linearly, the yaw along the shorter
/// arc (from 170 to -170 through 180, not through 0). f = 0 gives a, f = 1 gives b (yaw wrapped).
[[nodiscard]] Pose2 interpolate(const Pose2& a, const Pose2& b, double f);

/// Euclidean distance between the positions (the headings do not count).
[[nodiscard]] double distance_cm(const Pose2& a, const Pose2& b);

/// Signed heading difference a - b along the shorter arc, in (-180, 180] degrees.
[[nodiscard]] double yaw_difference_deg(const Pose2& a, const Pose2& b);

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
