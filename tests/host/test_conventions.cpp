// Conventions: angle wrapping, frame rotations, the Pose2 algebra and equation (9), against
// hand-computed values.
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
  // Rotation in place moves every wheel by R omega.
  const Eigen::Vector4d rot = j * Eigen::Vector3d(0.0, 0.0, 2.0);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(rot(i), 2.0 * R, 1e-12);
}

// At 45 degrees sin = cos, so a Jacobian with sin and cos swapped passes every test there. At 30
// degrees: sin = 0.5, cos = sqrt(3)/2 = 0.8660254037844386, worked by hand from equation (9):
//   row 1: [-0.5, -0.8660254037844386, 20]   row 2: [-0.5, 0.8660254037844386, 20]
//   row 3: [ 0.5, -0.8660254037844386, 20]   row 4: [ 0.5, 0.8660254037844386, 20]
// and for Vx = 10 cm/s, Vy = 4 cm/s, omega = 0.5 rad/s (R omega = 10, 4 cos = 3.4641016151377544):
//   V1 = -5 - 3.4641016151377544 + 10 =  1.5358983848622456
//   V2 = -5 + 3.4641016151377544 + 10 =  8.4641016151377544
//   V3 =  5 - 3.4641016151377544 + 10 = 11.5358983848622456
//   V4 =  5 + 3.4641016151377544 + 10 = 18.4641016151377544
TEST(Conventions, WheelJacobianAt30DegreesByHand) {
  const auto j = wheel_jacobian(30.0, 20.0);
  const double expected[4][3] = {{-0.5, -0.8660254037844386, 20.0},
                                 {-0.5, 0.8660254037844386, 20.0},
                                 {0.5, -0.8660254037844386, 20.0},
                                 {0.5, 0.8660254037844386, 20.0}};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(j(r, c), expected[r][c], 1e-12) << "row " << r + 1 << " col " << c + 1;
  const Eigen::Vector4d v = j * Eigen::Vector3d(10.0, 4.0, 0.5);
  EXPECT_NEAR(v(0), 1.5358983848622456, 1e-12);
  EXPECT_NEAR(v(1), 8.4641016151377544, 1e-12);
  EXPECT_NEAR(v(2), 11.5358983848622456, 1e-12);
  EXPECT_NEAR(v(3), 18.4641016151377544, 1e-12);
}

void expect_pose_near(const Pose2& got, const Pose2& want, double tol = 1e-9) {
  EXPECT_NEAR(got.x_cm, want.x_cm, tol);
  EXPECT_NEAR(got.y_cm, want.y_cm, tol);
  EXPECT_NEAR(angle_diff_deg(got.yaw_deg, want.yaw_deg), 0.0, tol)
      << got.yaw_deg << " vs " << want.yaw_deg;
}

// a = (100, 50) facing +y (90 deg). 10 cm forward in a's frame is +10 along field y; (10, 5) in
// a's frame is R(90) (10, 5) = (-5, 10) in the field, and the headings add.
TEST(Pose2Algebra, ComposeWithA90DegreeTurnByHand) {
  const Pose2 a{100.0, 50.0, 90.0};
  expect_pose_near(a * Pose2{10.0, 0.0, 0.0}, {100.0, 60.0, 90.0});
  expect_pose_near(a * Pose2{10.0, 5.0, 90.0}, {95.0, 60.0, 180.0});
  expect_pose_near(compose(a, Pose2{10.0, 5.0, 90.0}), {95.0, 60.0, 180.0});
  // The other order: (10, 5, 90) then a's (100, 50) in that frame: R(90) (100, 50) = (-50, 100).
  expect_pose_near(Pose2{10.0, 5.0, 90.0} * a, {-40.0, 105.0, 180.0});
  // 30 degrees: 2 cm forward is (2 cos 30, 2 sin 30) = (sqrt 3, 1).
  expect_pose_near(Pose2{0.0, 0.0, 30.0} * Pose2{2.0, 0.0, 0.0}, {std::sqrt(3.0), 1.0, 30.0});
  // Headings stay wrapped: 170 + 20 = -170.
  EXPECT_NEAR((Pose2{0, 0, 170.0} * Pose2{0, 0, 20.0}).yaw_deg, -170.0, 1e-12);
  // A point in a's frame: 1 cm ahead of a is (100, 51).
  const Eigen::Vector2d p = a * Eigen::Vector2d(1.0, 0.0);
  EXPECT_NEAR(p.x(), 100.0, 1e-12);
  EXPECT_NEAR(p.y(), 51.0, 1e-12);
  Pose2 b = a;
  b *= Pose2{10.0, 0.0, 0.0};
  expect_pose_near(b, {100.0, 60.0, 90.0});
}

// a^-1 = (-R(-90) (100, 50), -90) = (-50, 100, -90) by hand; composed either way: the identity.
TEST(Pose2Algebra, InverseComposedGivesIdentity) {
  const Pose2 a{100.0, 50.0, 90.0};
  expect_pose_near(a.inverse(), {-50.0, 100.0, -90.0});
  for (const Pose2& p :
       {a, Pose2{-3.0, 7.5, -135.0}, Pose2{375.0, 275.0, 180.0}, Pose2{1.0, 2.0, 33.3}}) {
    expect_pose_near(p * p.inverse(), {0.0, 0.0, 0.0});
    expect_pose_near(p.inverse() * p, {0.0, 0.0, 0.0});
    // The relative pose of q seen from p, carried back by p, is q.
    const Pose2 q{12.0, -4.0, 170.0};
    expect_pose_near(p * (p.inverse() * q), q);
  }
  // Associativity.
  const Pose2 b{10.0, 5.0, 30.0}, c{-2.0, 8.0, -100.0};
  expect_pose_near((a * b) * c, a * (b * c));
}

TEST(Pose2Algebra, InterpolationIsLinearAndTakesTheShortArcAcrossTheSeam) {
  const Pose2 a{0.0, 0.0, 170.0}, b{10.0, 20.0, -170.0};
  // 20 degrees apart through 180, not 340 through 0.
  expect_pose_near(interpolate(a, b, 0.5), {5.0, 10.0, 180.0});
  expect_pose_near(interpolate(a, b, 0.25), {2.5, 5.0, 175.0});
  expect_pose_near(interpolate(a, b, 0.75), {7.5, 15.0, -175.0});
  expect_pose_near(interpolate(b, a, 0.5), {5.0, 10.0, 180.0});
  expect_pose_near(interpolate(a, b, 0.0), a);
  expect_pose_near(interpolate(a, b, 1.0), b);
  // Away from the seam: plain linear yaw.
  expect_pose_near(interpolate(Pose2{0, 0, 10.0}, Pose2{0, 0, 50.0}, 0.25), {0.0, 0.0, 20.0});
  EXPECT_NEAR(interpolate_deg(-170.0, 170.0, 0.25), -175.0, 1e-12);
  EXPECT_NEAR(interpolate_deg(350.0, 10.0, 0.5), 0.0, 1e-12);  // inputs need not be wrapped
  EXPECT_GE(interpolate(a, b, 0.5).yaw_deg, -180.0);
  EXPECT_LE(interpolate(a, b, 0.5).yaw_deg, 180.0);
}

// A field-frame shift moves along the field's axes whatever the heading (unlike `*`, which moves
// along the pose's own): (100, 50, 90) shifted by (10, 0) is (110, 50, 90), while * (10, 0, 0)
// gives (100, 60, 90). with_yaw keeps the position and wraps the heading.
TEST(Pose2Algebra, FieldFrameShiftAndNewHeadingByHand) {
  const Pose2 a{100.0, 50.0, 90.0};
  expect_pose_near(a.shifted({10.0, 0.0}), {110.0, 50.0, 90.0});
  expect_pose_near(a * Pose2{10.0, 0.0, 0.0}, {100.0, 60.0, 90.0});
  expect_pose_near(a.shifted({-3.0, 4.5}).shifted({3.0, -4.5}), a);
  expect_pose_near(a.with_yaw(190.0), {100.0, 50.0, -170.0});
  // The localizer's anchor carried forward: the anchor moves as the odometry did, in the field
  // frame, and takes the odometry's heading.
  const Pose2 odo_then{20.0, 30.0, 45.0}, odo_now{25.0, 28.0, 60.0};
  const Pose2 carried =
      a.shifted(odo_now.position_cm() - odo_then.position_cm()).with_yaw(odo_now.yaw_deg);
  expect_pose_near(carried, {105.0, 48.0, 60.0});
}

TEST(Pose2Algebra, DistanceAndYawDifference) {
  EXPECT_DOUBLE_EQ(distance_cm(Pose2{1.0, 2.0, 0.0}, Pose2{4.0, 6.0, 90.0}),
                   5.0);  // 3-4-5, heading ignored
  EXPECT_DOUBLE_EQ(yaw_difference_deg(Pose2{0, 0, 10.0}, Pose2{0, 0, 350.0}), 20.0);
  EXPECT_DOUBLE_EQ(yaw_difference_deg(Pose2{0, 0, -170.0}, Pose2{0, 0, 170.0}), 20.0);
  EXPECT_DOUBLE_EQ(yaw_difference_deg(Pose2{0, 0, 170.0}, Pose2{0, 0, -170.0}), -20.0);
  EXPECT_TRUE((Pose2{1.0, 2.0, 3.0} == Pose2{1.0, 2.0, 3.0}));
  EXPECT_FALSE((Pose2{1.0, 2.0, 3.0} == Pose2{1.0, 2.0, 3.5}));
}

}  // namespace
}  // namespace omniloc
