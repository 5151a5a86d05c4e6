#include "omniloc/conventions.hpp"

#include <cmath>

namespace omniloc {

double wrap_deg(double angle_deg) {
  double wrapped = std::fmod(angle_deg, 360.0);
  if (wrapped <= -180.0) wrapped += 360.0;
  if (wrapped > 180.0) wrapped -= 360.0;
  return wrapped;
}

double angle_diff_deg(double a_deg, double b_deg) {
  return wrap_deg(a_deg - b_deg);
}

double interpolate_deg(double a_deg, double b_deg, double f) {
  return wrap_deg(a_deg + f * angle_diff_deg(b_deg, a_deg));
}

Eigen::Vector2d robot_to_field(const Eigen::Vector2d& v_robot, double yaw_deg) {
  const double c = std::cos(deg_to_rad(yaw_deg));
  const double s = std::sin(deg_to_rad(yaw_deg));
  return {c * v_robot.x() - s * v_robot.y(), s * v_robot.x() + c * v_robot.y()};
}

Eigen::Vector2d field_to_robot(const Eigen::Vector2d& v_field, double yaw_deg) {
  return robot_to_field(v_field, -yaw_deg);
}

Pose2 Pose2::operator*(const Pose2& local) const {
  const Eigen::Vector2d p = *this * local.position_cm();
  return {p.x(), p.y(), wrap_deg(yaw_deg + local.yaw_deg)};
}

Eigen::Vector2d Pose2::operator*(const Eigen::Vector2d& p_local_cm) const {
  return position_cm() + robot_to_field(p_local_cm, yaw_deg);
}

Pose2 Pose2::inverse() const {
  // (R, t)^-1 = (R^T, -R^T t).
  const Eigen::Vector2d t = field_to_robot(-position_cm(), yaw_deg);
  return {t.x(), t.y(), wrap_deg(-yaw_deg)};
}

Pose2 Pose2::with_yaw(double new_yaw_deg) const {
  return {x_cm, y_cm, wrap_deg(new_yaw_deg)};
}

Pose2 interpolate(const Pose2& a, const Pose2& b, double f) {
  return {a.x_cm + f * (b.x_cm - a.x_cm), a.y_cm + f * (b.y_cm - a.y_cm),
          interpolate_deg(a.yaw_deg, b.yaw_deg, f)};
}

double distance_cm(const Pose2& a, const Pose2& b) {
  return (a.position_cm() - b.position_cm()).norm();
}

double yaw_difference_deg(const Pose2& a, const Pose2& b) {
  return angle_diff_deg(a.yaw_deg, b.yaw_deg);
}

Eigen::Matrix<double, 4, 3> wheel_jacobian(double motor_angle_deg, double center_to_wheel_cm) {
  const double s = std::sin(deg_to_rad(motor_angle_deg));
  const double c = std::cos(deg_to_rad(motor_angle_deg));
  const double r = center_to_wheel_cm;
  Eigen::Matrix<double, 4, 3> j;
  j << -s, -c, r,  //
      -s, c, r,    //
      s, -c, r,    //
      s, c, r;
  return j;
}

}  // namespace omniloc
