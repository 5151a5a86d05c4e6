// Conventions: angle wrapping, frame rotations and equation (9), against hand-computed values.
#include <gtest/gtest.h>

#include <cmath>

#include "omniloc/conventions.hpp"

namespace omniloc {
namespace {

TEST(Conventions, WrapDegIntoHalfOpenRange) {
  EXPECT_DOUBLE_EQ(wrap_deg(0.0), 0.0);
  EXPECT_DOUBLE_EQ(wrap_deg(180.0), 180.0);
  EXPECT_DOUBLE_EQ(wrap_deg(-180.0), 180.0);
  EXPECT_DOUBLE_EQ(wrap_deg(190.0), -170.0);
  EXPECT_DOUBLE_EQ(wrap_deg(-190.0), 170.0);
  EXPECT_DOUBLE_EQ(wrap_deg(720.0 + 45.0), 45.0);
  EXPECT_DOUBLE_EQ(angle_diff_deg(10.0, 350.0), 20.0);
  EXPECT_DOUBLE_EQ(angle_diff_deg(350.0, 10.0), -20.0);
}

TEST(Conventions, RobotForwardAtYaw90PointsAlongFieldY) {
  const Eigen::Vector2d f = robot_to_field({1.0, 0.0}, 90.0);
  EXPECT_NEAR(f.x(), 0.0, 1e-12);
  EXPECT_NEAR(f.y(), 1.0, 1e-12);
  // Robot's left (+y) at yaw 90 points along field -x.
  const Eigen::Vector2d l = robot_to_field({0.0, 1.0}, 90.0);
  EXPECT_NEAR(l.x(), -1.0, 1e-12);
  EXPECT_NEAR(l.y(), 0.0, 1e-12);
  const Eigen::Vector2d back = field_to_robot(robot_to_field({3.0, -4.0}, 37.0), 37.0);
  EXPECT_NEAR(back.x(), 3.0, 1e-12);
  EXPECT_NEAR(back.y(), -4.0, 1e-12);
}

TEST(Conventions, WheelJacobianMatchesEquation9) {
  const double R = 20.0;
  const auto j = wheel_jacobian(45.0, R);
  const double h = std::sqrt(0.5);
  // Pure forward motion Vx = 10 cm/s: wheels 1,2 see -10 h, wheels 3,4 see +10 h.
  const Eigen::Vector4d v = j * Eigen::Vector3d(10.0, 0.0, 0.0);
  EXPECT_NEAR(v(0), -10.0 * h, 1e-12);
  EXPECT_NEAR(v(1), -10.0 * h, 1e-12);
  EXPECT_NEAR(v(2), 10.0 * h, 1e-12);
  EXPECT_NEAR(v(3), 10.0 * h, 1e-12);
  // Equation (8) for wheel 2: -sin(tm) Vx + cos(tm) Vy + R omega.
  const Eigen::Vector4d w = j * Eigen::Vector3d(3.0, 5.0, 0.5);
  EXPECT_NEAR(w(1), -h * 3.0 + h * 5.0 + R * 0.5, 1e-12);
  // Rotation in place moves every wheel by R omega.
  const Eigen::Vector4d rot = j * Eigen::Vector3d(0.0, 0.0, 2.0);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(rot(i), 2.0 * R, 1e-12);
}

}  // namespace
}  // namespace omniloc
