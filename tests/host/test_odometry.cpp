// Odometry units against hand-computed values: eq. (9)'s pseudo-inverse, single windows with known
// motion, mid-window heading, timestamps, origin reset, uncertainty, slip isolation, and the paper
// variant's equations (10)-(15) evaluated by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "omniloc/odometry.hpp"

namespace omniloc {
namespace {

const double kS = std::sin(deg_to_rad(45.0));

// Counts for a body-frame motion (cm, cm, rad) through eq. (9), rounded.
std::array<std::int32_t, 4> counts_for(const RobotConfig& r, double dx, double dy, double dth) {
  const Eigen::Vector4d travel = wheel_jacobian(r.motor_angle_deg, r.center_to_wheel_cm) * Eigen::Vector3d(dx, dy, dth);
  std::array<std::int32_t, 4> c{};
  for (int i = 0; i < 4; ++i) c[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(std::lround(travel[i] / cm_per_count(r)));
  return c;
}

TEST(OdometryMath, PseudoInverseHandValues) {
  const RobotConfig r;
  const auto p = wheel_pseudo_inverse(r);
  // J^T J = diag(4 s^2, 4 c^2, 4 R^2) = diag(2, 2, 1600), so J+ = diag(1/2, 1/2, 1/1600) J^T.
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(p(0, i), (i < 2 ? -kS : kS) / 2.0, 1e-12);
    EXPECT_NEAR(p(1, i), (i % 2 == 0 ? -kS : kS) / 2.0, 1e-12);
    EXPECT_NEAR(p(2, i), 20.0 / 1600.0, 1e-12);
  }
  EXPECT_NEAR(cm_per_count(r), 2.0 * kPi * 5.0 / 38000.0, 1e-15);
}

TEST(Odometry, ForwardWindowMovesForwardInTheFieldFrame) {
  const RobotConfig r;
  Odometry odo(r);
  odo.reset({100.0, 200.0, 90.0});
  // 1.5 cm forward in 10 ms at heading 90: the field y grows by 1.5.
  const auto& e = odo.update({0, 10.0, counts_for(r, 1.5, 0.0, 0.0), 90.0});
  EXPECT_NEAR(e.pose.x_cm, 100.0, 1e-3);
  EXPECT_NEAR(e.pose.y_cm, 201.5, 1e-3);
  EXPECT_DOUBLE_EQ(e.pose.yaw_deg, 90.0);
  EXPECT_NEAR(e.speed_cm_per_s, 150.0, 0.1);
  EXPECT_FALSE(e.slip.detected);
}

// One window at constant twist v = (100, 40) cm/s, omega = 120 deg/s for 10 ms from yaw 30.
// Exact end point: p0 + R(yaw0) [sin(a)/w, -(1-cos a)/w; (1-cos a)/w, sin(a)/w] v with a = w T.
TEST(Odometry, MidWindowHeadingGivesTheExactChord) {
  const RobotConfig r;
  const double w = deg_to_rad(120.0), t = 0.01, a = w * t;
  const Eigen::Vector2d v(100.0, 40.0);
  const Eigen::Vector2d chord_body(std::sin(a) / w * v.x() - (1 - std::cos(a)) / w * v.y(),
                                   (1 - std::cos(a)) / w * v.x() + std::sin(a) / w * v.y());
  const Eigen::Vector2d expect = robot_to_field(chord_body, 30.0);
  Odometry odo(r);
  odo.reset({0.0, 0.0, 30.0});
  const auto& e = odo.update({0, 10.0, counts_for(r, v.x() * t, v.y() * t, a), 30.0 + rad_to_deg(a)});
  EXPECT_NEAR(e.pose.x_cm, expect.x(), 2e-3);
  EXPECT_NEAR(e.pose.y_cm, expect.y(), 2e-3);
  EXPECT_NEAR(e.wheel_yaw_deg, 30.0 + 1.2, 2e-3);
  // The start heading instead of the mid heading would be off by 0.6 deg * 1.08 cm = 0.011 cm.
  EXPECT_GT((robot_to_field(v * t, 30.0) - expect).norm(), 0.01);
}

TEST(Odometry, TimeComesFromWindowTimestamps) {
  const RobotConfig r;
  Odometry odo(r);
  odo.reset({0.0, 0.0, 0.0});
  (void)odo.update({0, 10.0, counts_for(r, 1.0, 0.0, 0.0), 0.0});
  const auto& e = odo.update({1, 18.0, counts_for(r, 1.0, 0.0, 0.0), 0.0});  // an 8 ms window
  EXPECT_NEAR(e.speed_cm_per_s, 125.0, 0.1);
  try {
    (void)odo.update({2, 18.0, counts_for(r, 1.0, 0.0, 0.0), 0.0});
    FAIL() << "no throw";
  } catch (const std::invalid_argument& err) {
    EXPECT_NE(std::string(err.what()).find("seq 2"), std::string::npos) << err.what();
  }
  EXPECT_THROW((void)odo.update({3, NAN, {}, 0.0}), std::invalid_argument);
}

TEST(Odometry, GyroWrapAndOriginReset) {
  const RobotConfig r;
  Odometry odo(r);
  odo.reset({0.0, 0.0, 179.0});
  (void)odo.update({0, 10.0, counts_for(r, 0.0, 0.0, deg_to_rad(2.0)), -179.0});  // across +-180
  EXPECT_NEAR(odo.estimate().pose.yaw_deg, -179.0, 1e-9);
  EXPECT_NEAR(odo.estimate().yaw_rate_deg_per_s, 200.0, 1e-6);
  // The gyro reads -179 but the image says the robot faces 10 deg at (50, 60): yaw follows.
  odo.reset({50.0, 60.0, 10.0}, 2.0, 0.5);
  EXPECT_DOUBLE_EQ(odo.estimate().sigma_xy_cm, 2.0);
  EXPECT_DOUBLE_EQ(odo.estimate().distance_cm, 0.0);
  const auto& e = odo.update({1, 20.0, counts_for(r, 1.0, 0.0, deg_to_rad(1.0)), -178.0});
  EXPECT_NEAR(e.pose.yaw_deg, 11.0, 1e-9);
  EXPECT_NEAR(e.pose.x_cm, 50.0 + std::cos(deg_to_rad(10.5)), 2e-3);
  EXPECT_NEAR(e.pose.y_cm, 60.0 + std::sin(deg_to_rad(10.5)), 2e-3);
  EXPECT_GT(e.sigma_xy_cm, 2.0);
}

TEST(Odometry, UncertaintyGrowsWithDistanceAndMoreWithSlip) {
  const RobotConfig r;
  Odometry clean(r), slipping(r);
  clean.reset({0, 0, 0});
  slipping.reset({0, 0, 0});
  double prev = 0.0;
  for (std::uint32_t k = 0; k < 100; ++k) {
    const auto c = counts_for(r, 1.0, 0.0, 0.0);
    auto s = c;
    if (k >= 50 && k < 55) s[1] += 600;  // ~0.5 cm of spin on wheel 2
    const auto& e = clean.update({k, 10.0 * (k + 1), c, 0.0});
    (void)slipping.update({k, 10.0 * (k + 1), s, 0.0});
    EXPECT_GT(e.sigma_xy_cm, prev);
    prev = e.sigma_xy_cm;
  }
  // 100 cm at 0.5 % plus the heading term: at least 0.5 cm.
  EXPECT_GT(clean.estimate().sigma_xy_cm, 0.5);
  EXPECT_GT(slipping.estimate().sigma_xy_cm, clean.estimate().sigma_xy_cm + 2.0);
}

// Each wheel in turn spins 0.4 cm extra during a steady 1 cm/window drive: the isolation must
// name it (the motion prior tells diagonal partners apart) and the pose must not take the spin.
TEST(Odometry, SlipIsIsolatedToTheRightWheelAndRejected) {
  const RobotConfig r;
  for (int wheel = 1; wheel <= 4; ++wheel) {
    SCOPED_TRACE(wheel);
    Odometry odo(r);
    odo.reset({0, 0, 0});
    for (std::uint32_t k = 0; k < 20; ++k) {
      auto c = counts_for(r, 0.8, 0.6, 0.0);
      const bool slip = k == 12;
      if (slip) c[static_cast<std::size_t>(wheel - 1)] += static_cast<std::int32_t>(std::lround((wheel % 2 ? -0.4 : 0.4) / cm_per_count(r)));
      const auto& e = odo.update({k, 10.0 * (k + 1), c, 0.0});
      EXPECT_EQ(e.slip.detected, slip);
      if (slip) {
        EXPECT_EQ(e.slip.wheel, wheel);
        EXPECT_NEAR(std::abs(e.slip.magnitude_cm), 0.4, 0.01);
      }
    }
    EXPECT_NEAR(odo.estimate().pose.x_cm, 16.0, 0.01);
    EXPECT_NEAR(odo.estimate().pose.y_cm, 12.0, 0.01);
  }
}

// Paper variant by hand. Forward 1 cm: D = (-s,-s,s,s), d = 0, S sums to 0: no motion at all.
TEST(PaperOdometry, PureTranslationCancelsInEquation13) {
  const RobotConfig r;
  PaperOdometry p(r);
  p.reset({100.0, 100.0, 0.0});
  (void)p.update({0, 10.0, counts_for(r, 1.0, 0.0, 0.0), 0.0});
  EXPECT_NEAR(p.estimate().pose.x_cm, 100.0, 1e-9);
  EXPECT_NEAR(p.estimate().pose.y_cm, 100.0, 1e-9);
}

// Rotation by theta in place: D_i = R theta, d = R theta / 2 (eq. 11), S_i = R theta / 2,
// Sx = 1/2 * 4 * (-cos 45) R theta / 2 = -c R theta, Sy = -s R theta: length R theta, direction
// atan(1) + yaw = 45 deg + yaw -- a rotation on the spot becomes a move of R theta.
TEST(PaperOdometry, RotationInPlaceMovesTheRobot) {
  const RobotConfig r;
  PaperOdometry p(r);
  p.reset({100.0, 100.0, 0.0});
  const double th = deg_to_rad(1.0);
  const auto c = counts_for(r, 0.0, 0.0, th);
  (void)p.update({0, 10.0, c, 1.0});
  const double d_i = c[0] * cm_per_count(r);  // eq. (10) with T = 0.01 s
  const double len = std::sqrt(2.0) * 2.0 * kS * (d_i - 20.0 * th / 2.0);
  EXPECT_NEAR(p.estimate().pose.x_cm, 100.0 + len * std::cos(deg_to_rad(46.0)), 1e-9);
  EXPECT_NEAR(p.estimate().pose.y_cm, 100.0 + len * std::sin(deg_to_rad(46.0)), 1e-9);
  EXPECT_NEAR(len, 20.0 * th, 1e-3);
}

// Eq. (10) assumes T = 0.01 s in "res x 0.01": with a nominal 8 ms window the distance scales by 0.8.
TEST(PaperOdometry, Equation10UsesTheNominalPeriod) {
  RobotConfig r;
  r.window_period_ms = 8.0;
  PaperOdometry p(r);
  p.reset({0.0, 0.0, 0.0});
  const double th = deg_to_rad(1.0);
  (void)p.update({0, 8.0, counts_for(r, 0.0, 0.0, th), 1.0});
  const double d_i = counts_for(r, 0.0, 0.0, th)[0] * cm_per_count(r) * 0.8;
  EXPECT_NEAR(std::hypot(p.estimate().pose.x_cm, p.estimate().pose.y_cm), 2.0 * (d_i - 20.0 * th / 2.0), 1e-9);
}

}  // namespace
}  // namespace omniloc
