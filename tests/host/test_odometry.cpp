// Odometry units against hand-computed values: eq. (9)'s pseudo-inverse, single windows with known
// motion, mid-window heading, timestamps, origin reset, uncertainty, slip isolation, and the paper
// variant's equations (10)-(15) evaluated by hand.
//
// The wheel inputs are made here from the wheels' geometry, never through wheel_jacobian (the code
// under test): wheel i rolls along a direction at angle alpha_i in the robot frame and sits R from
// the centre, so over a body motion (dx, dy, dtheta) its rim travels
//   dx cos(alpha_i) + dy sin(alpha_i) + R dtheta,
// with alpha = 270 - tm, 90 + tm, tm - 90, 90 - tm for wheels 1..4 (the sign pattern of eq. (9):
// at tm = 45 the four wheels roll along 225, 135, -45 and 45 degrees). The tests run at tm = 45 and
// tm = 30: at 45 sin = cos and a Jacobian with the two swapped would go unnoticed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "omniloc/odometry.hpp"

namespace omniloc {
namespace {

/// One window: seq, end time, counts, gyro yaw (the rest as a board without a gyro gives it).
EncoderWindow win(std::uint32_t seq, double t_end_ms, const std::array<std::int32_t, 4>& counts,
                  double gyro_yaw_deg) {
  EncoderWindow w;
  w.seq = seq;
  w.t_end_ms = t_end_ms;
  w.counts = counts;
  w.gyro_yaw_deg = gyro_yaw_deg;
  return w;
}

const double kS = std::sin(deg_to_rad(45.0));

// Rim travel (cm) of each wheel for a body-frame motion (cm, cm, rad), from the wheel geometry.
std::array<double, 4> rim_travel_cm(const RobotConfig& r, double dx, double dy, double dth) {
  const double tm = r.motor_angle_deg;
  const double alpha_deg[4] = {270.0 - tm, 90.0 + tm, tm - 90.0, 90.0 - tm};
  std::array<double, 4> t{};
  for (int i = 0; i < 4; ++i) {
    const double a = alpha_deg[i] * kPi / 180.0;
    t[static_cast<std::size_t>(i)] =
        dx * std::cos(a) + dy * std::sin(a) + r.center_to_wheel_cm * dth;
  }
  return t;
}

// Counts for a body-frame motion, rounded: cm per count = 2 pi r / (counts_per_rev x decoding x N).
std::array<std::int32_t, 4> counts_for(const RobotConfig& r, double dx, double dy, double dth) {
  const double cm_per_count_by_hand =
      2.0 * kPi * r.wheel_radius_cm / (r.counts_per_rev * r.decoding * r.gear_ratio);
  const std::array<double, 4> t = rim_travel_cm(r, dx, dy, dth);
  std::array<std::int32_t, 4> c{};
  for (int i = 0; i < 4; ++i)
    c[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(
        std::lround(t[static_cast<std::size_t>(i)] / cm_per_count_by_hand));
  return c;
}

RobotConfig robot_at(double motor_angle_deg) {
  RobotConfig r;
  r.motor_angle_deg = motor_angle_deg;
  return r;
}

TEST(OdometryMath, WheelGeometryHandNumbersAt30Degrees) {
  // The helper above against numbers worked by hand: 1.5 cm forward at tm = 30 moves wheels 1, 2 by
  // -1.5 sin 30 = -0.75 cm and wheels 3, 4 by +0.75; 1 cm left moves them by -cos 30, +cos 30,
  // -cos 30, +cos 30 = -+0.8660254037844386; 0.01 rad in place moves each by R x 0.01 = 0.2 cm.
  const RobotConfig r = robot_at(30.0);
  const auto fwd = rim_travel_cm(r, 1.5, 0.0, 0.0);
  const auto left = rim_travel_cm(r, 0.0, 1.0, 0.0);
  const auto turn = rim_travel_cm(r, 0.0, 0.0, 0.01);
  const double want_fwd[4] = {-0.75, -0.75, 0.75, 0.75};
  const double want_left[4] = {-0.8660254037844386, 0.8660254037844386, -0.8660254037844386,
                               0.8660254037844386};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(fwd[i], want_fwd[i], 1e-12) << i;
    EXPECT_NEAR(left[i], want_left[i], 1e-12) << i;
    EXPECT_NEAR(turn[i], 0.2, 1e-12) << i;
  }
  // 38000 counts per wheel turn of 2 pi 5 cm: 0.75 cm is 907.2 -> 907 counts.
  EXPECT_EQ(counts_for(r, 1.5, 0.0, 0.0)[2], 907);
}

// At tm = 30: J^T J = diag(4 sin^2, 4 cos^2, 4 R^2) = diag(1, 3, 1600) (the columns stay
// orthogonal), so J+ = diag(1, 1/3, 1/1600) J^T: row 1 = (-0.5, -0.5, 0.5, 0.5), row 2 = cos 30 / 3
// x (-1, 1, -1, 1) = (-+)0.28867513459481287, row 3 = 20 / 1600 = 0.0125 everywhere.
TEST(OdometryMath, PseudoInverseHandValuesAt30Degrees) {
  const auto p = wheel_pseudo_inverse(robot_at(30.0));
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(p(0, i), i < 2 ? -0.5 : 0.5, 1e-12) << i;
    EXPECT_NEAR(p(1, i), i % 2 == 0 ? -0.28867513459481287 : 0.28867513459481287, 1e-12) << i;
    EXPECT_NEAR(p(2, i), 0.0125, 1e-12) << i;
  }
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
  const auto& e = odo.update(win(0, 10.0, counts_for(r, 1.5, 0.0, 0.0), 90.0));
  EXPECT_NEAR(e.pose.x_cm, 100.0, 1e-3);
  EXPECT_NEAR(e.pose.y_cm, 201.5, 1e-3);
  EXPECT_DOUBLE_EQ(e.pose.yaw_deg, 90.0);
  EXPECT_NEAR(e.speed_cm_per_s, 150.0, 0.1);
  EXPECT_FALSE(e.slip.detected);
}

// At tm = 30 a sideways motion: 0.6 cm forward and 0.8 cm left in 10 ms at heading 0 (the wheel
// counts by hand: -0.3 - 0.69282 = -0.99282 cm on wheel 1, ...), read back as (0.6, 0.8) to the
// counts' rounding (1/1209.6 cm).
TEST(Odometry, DiagonalWindowAt30Degrees) {
  for (const double tm : {30.0, 60.0}) {
    SCOPED_TRACE(tm);
    const RobotConfig r = robot_at(tm);
    Odometry odo(r);
    odo.reset({10.0, 20.0, 0.0});
    const auto& e = odo.update(win(0, 10.0, counts_for(r, 0.6, 0.8, 0.0), 0.0));
    EXPECT_NEAR(e.pose.x_cm, 10.6, 2e-3);
    EXPECT_NEAR(e.pose.y_cm, 20.8, 2e-3);
    EXPECT_NEAR(e.speed_cm_per_s, 100.0, 0.2);
    EXPECT_FALSE(e.slip.detected);
  }
}

// One window at constant twist v = (100, 40) cm/s, omega = 120 deg/s for 10 ms from yaw 30.
// Exact end point: p0 + R(yaw0) [sin(a)/w, -(1-cos a)/w; (1-cos a)/w, sin(a)/w] v with a = w T.
TEST(Odometry, MidWindowHeadingGivesTheExactChord) {
  for (const double tm : {45.0, 30.0}) {
    SCOPED_TRACE(tm);
    const RobotConfig r = robot_at(tm);
    const double w = deg_to_rad(120.0), t = 0.01, a = w * t;
    const Eigen::Vector2d v(100.0, 40.0);
    const Eigen::Vector2d chord_body(std::sin(a) / w * v.x() - (1 - std::cos(a)) / w * v.y(),
                                     (1 - std::cos(a)) / w * v.x() + std::sin(a) / w * v.y());
    const Eigen::Vector2d expect = robot_to_field(chord_body, 30.0);
    Odometry odo(r);
    odo.reset({0.0, 0.0, 30.0});
    const auto& e =
        odo.update(win(0, 10.0, counts_for(r, v.x() * t, v.y() * t, a), 30.0 + rad_to_deg(a)));
    EXPECT_NEAR(e.pose.x_cm, expect.x(), 2e-3);
    EXPECT_NEAR(e.pose.y_cm, expect.y(), 2e-3);
    EXPECT_NEAR(e.wheel_yaw_deg, 30.0 + 1.2, 2e-3);
    // The start heading instead of the mid heading would be off by 0.6 deg * 1.08 cm = 0.011 cm.
    EXPECT_GT((robot_to_field(v * t, 30.0) - expect).norm(), 0.01);
  }
}

TEST(Odometry, TimeComesFromWindowTimestamps) {
  const RobotConfig r;
  Odometry odo(r);
  odo.reset({0.0, 0.0, 0.0});
  (void)odo.update(win(0, 10.0, counts_for(r, 1.0, 0.0, 0.0), 0.0));
  const auto& e = odo.update(win(1, 18.0, counts_for(r, 1.0, 0.0, 0.0), 0.0));  // an 8 ms window
  EXPECT_NEAR(e.speed_cm_per_s, 125.0, 0.1);
  try {
    (void)odo.update(win(2, 18.0, counts_for(r, 1.0, 0.0, 0.0), 0.0));
    FAIL() << "no throw";
  } catch (const std::invalid_argument& err) {
    EXPECT_NE(std::string(err.what()).find("seq 2"), std::string::npos) << err.what();
  }
  EXPECT_THROW((void)odo.update(win(3, NAN, {}, 0.0)), std::invalid_argument);
}

TEST(Odometry, GyroWrapAndOriginReset) {
  const RobotConfig r;
  Odometry odo(r);
  odo.reset({0.0, 0.0, 179.0});
  (void)odo.update(win(0, 10.0, counts_for(r, 0.0, 0.0, deg_to_rad(2.0)), -179.0));  // across +-180
  EXPECT_NEAR(odo.estimate().pose.yaw_deg, -179.0, 1e-9);
  EXPECT_NEAR(odo.estimate().yaw_rate_deg_per_s, 200.0, 1e-6);
  // The gyro reads -179 but the image says the robot faces 10 deg at (50, 60): yaw follows.
  odo.reset({50.0, 60.0, 10.0}, 2.0, 0.5);
  EXPECT_DOUBLE_EQ(odo.estimate().sigma_xy_cm, 2.0);
  EXPECT_DOUBLE_EQ(odo.estimate().distance_cm, 0.0);
  const auto& e = odo.update(win(1, 20.0, counts_for(r, 1.0, 0.0, deg_to_rad(1.0)), -178.0));
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
    const auto& e = clean.update(win(k, 10.0 * (k + 1), c, 0.0));
    (void)slipping.update(win(k, 10.0 * (k + 1), s, 0.0));
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
      if (slip)
        c[static_cast<std::size_t>(wheel - 1)] +=
            static_cast<std::int32_t>(std::lround((wheel % 2 ? -0.4 : 0.4) / cm_per_count(r)));
      const auto& e = odo.update(win(k, 10.0 * (k + 1), c, 0.0));
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
  (void)p.update(win(0, 10.0, counts_for(r, 1.0, 0.0, 0.0), 0.0));
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
  (void)p.update(win(0, 10.0, c, 1.0));
  const double d_i = c[0] * cm_per_count(r);  // eq. (10) with T = 0.01 s
  const double len = std::sqrt(2.0) * 2.0 * kS * (d_i - 20.0 * th / 2.0);
  EXPECT_NEAR(p.estimate().pose.x_cm, 100.0 + len * std::cos(deg_to_rad(46.0)), 1e-9);
  EXPECT_NEAR(p.estimate().pose.y_cm, 100.0 + len * std::sin(deg_to_rad(46.0)), 1e-9);
  EXPECT_NEAR(len, 20.0 * th, 1e-3);
}

// Eq. (10) assumes T = 0.01 s in "res x 0.01", the board's window period, whatever the window's
// timestamps say: a window that lasted 8 ms moves the paper variant as far as one of 10 ms.
TEST(PaperOdometry, Equation10UsesTheBoardsWindowPeriod) {
  const RobotConfig r;
  const double th = deg_to_rad(1.0);
  const auto travel_after_first_window = [&](double t_end_ms) {
    PaperOdometry p(r);
    p.reset({0.0, 0.0, 0.0});
    (void)p.update(win(0, t_end_ms, counts_for(r, 0.0, 0.0, th), 1.0));
    return std::hypot(p.estimate().pose.x_cm, p.estimate().pose.y_cm);
  };
  const double d_i = counts_for(r, 0.0, 0.0, th)[0] * cm_per_count(r);
  EXPECT_NEAR(travel_after_first_window(8.0), 2.0 * (d_i - 20.0 * th / 2.0), 1e-9);
  EXPECT_EQ(travel_after_first_window(8.0), travel_after_first_window(10.0));
}

}  // namespace
}  // namespace omniloc

namespace omniloc {
namespace {

// Issue (hostile input): the one check of a window's gyro yaw (GyroYawGuard in
// Localizer::on_window, for replay and the daemons alike), value by value.
TEST(GyroYawCheck, NotFiniteOutOfRangeAndJumpsBeyondTheRobotsTurnRate) {
  struct Case {
    double yaw;
    std::optional<double> previous;
    double dt_s;
    GyroYawFault fault;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<Case> cases = {
      {10.0, std::nullopt, 0.01, GyroYawFault::kNone},
      {10.0, 0.0, 0.01, GyroYawFault::kNone},      // 1000 deg/s: fast, possible
      {-170.0, 175.0, 0.01, GyroYawFault::kNone},  // across the wrap: 15 deg
      {16.0, 0.0, 0.01, GyroYawFault::kJump},      // 1600 deg/s > 1500
      {16.0, 0.0, 0.02, GyroYawFault::kNone},      // ... but not over a 20 ms window
      {nan, 0.0, 0.01, GyroYawFault::kNotFinite},
      {inf, std::nullopt, 0.01, GyroYawFault::kNotFinite},
      {1e6, 0.0, 0.01, GyroYawFault::kOutOfRange},
      {-400.0, std::nullopt, 0.01, GyroYawFault::kOutOfRange},
      {3600.0, 0.0, 0.01, GyroYawFault::kOutOfRange},
      {1e300, 0.0, 0.01, GyroYawFault::kOutOfRange},
      {-100.0, 30.0, 0.01, GyroYawFault::kJump},
  };
  for (const Case& c : cases) {
    const GyroYawCheck g = check_gyro_yaw(c.yaw, c.previous, c.dt_s, 1500.0);
    EXPECT_EQ(g.fault, c.fault) << c.yaw << " after " << c.previous.value_or(nan) << ": "
                                << g.describe();
  }
  const GyroYawCheck jump = check_gyro_yaw(-100.0, 30.0, 0.01, 1500.0);
  EXPECT_EQ(jump.describe(),
            "gyro_yaw_deg -100 jumped -130.000 deg since the last window, more than the 15.000 deg "
            "the robot can turn in it (max_yaw_rate_deg_per_s)");
  EXPECT_EQ(check_gyro_yaw(1e300, 0.0, 0.01, 1500.0).describe(),
            "gyro_yaw_deg 1e+300 is outside +-360 deg (headings are wrapped into (-180, 180])");
}

// A one-window spike is dropped and never followed (the wheels carry the heading over it); a
// jump that stays (the simulator's kidnap) is followed from the next window.
TEST(GyroYawGuard, DropsASpikeFollowsAStep) {
  const RobotConfig robot;
  GyroYawGuard guard(robot);
  auto window = [](std::uint32_t seq, double yaw) {
    EncoderWindow w;
    w.seq = seq;
    w.t_end_ms = 10.0 * seq;
    w.gyro_yaw_deg = yaw;
    return w;
  };
  std::vector<double> passed;
  const std::vector<double> raw = {30, 30.1, 1e6, 30.3, 30.4, 90, 90.1, 90.2};
  for (std::size_t i = 0; i < raw.size(); ++i) {
    EncoderWindow w = window(static_cast<std::uint32_t>(i + 1), raw[i]);
    (void)guard.screen(w);
    passed.push_back(w.gyro_yaw_deg);
  }
  // The wheels did not turn (no counts): the spike's window keeps the last good heading.
  const std::vector<double> want = {30, 30.1, 30.1, 30.3, 30.4, 30.4, 90.1, 90.2};
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_NEAR(passed[i], want[i], 1e-9) << "window " << i + 1;
  EXPECT_EQ(guard.dropped(), 2u);
}

}  // namespace
}  // namespace omniloc
