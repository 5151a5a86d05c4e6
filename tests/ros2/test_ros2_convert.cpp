// ROS 2 conventions by hand: topic names, quaternions, covariance layout, time stamps.
#include <gtest/gtest.h>

#include <cmath>

#include "omniloc/ros2_bridge.hpp"

namespace omniloc::ros2 {
namespace {

TEST(Ros2Convert, TopicNamesTakeTheRtPrefix) {
  EXPECT_EQ(dds_topic_name("/omniloc/pose"), "rt/omniloc/pose");
  EXPECT_EQ(dds_topic_name("/initialpose"), "rt/initialpose");
  for (const char* bad : {"", "omniloc/pose", "/", "/omniloc/", "/a//b", "/a b", "/9lives", "/a-b"})
    EXPECT_THROW((void)dds_topic_name(bad), std::invalid_argument) << bad;
}

TEST(Ros2Convert, YawQuaternionByHand) {
  // 90 deg about z: (0, 0, sin 45, cos 45).
  const QuaternionZ q = yaw_quaternion(90.0);
  EXPECT_NEAR(q.z, std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(q.w, std::sqrt(0.5), 1e-15);
  const QuaternionZ r = yaw_quaternion(180.0);
  EXPECT_NEAR(r.z, 1.0, 1e-15);
  EXPECT_NEAR(r.w, 0.0, 1e-15);
}

TEST(Ros2Convert, QuaternionYawOfAnyQuaternion) {
  EXPECT_NEAR(*quaternion_yaw_deg(0, 0, std::sqrt(0.5), std::sqrt(0.5)), 90.0, 1e-12);
  EXPECT_NEAR(*quaternion_yaw_deg(0, 0, 1, 0), 180.0, 1e-12);
  EXPECT_NEAR(*quaternion_yaw_deg(0, 0, -0.5, std::sqrt(0.75)), -60.0, 1e-12);
  // Unnormalised (RViz sends unit quaternions, a hand-typed `ros2 topic pub` may not).
  EXPECT_NEAR(*quaternion_yaw_deg(0, 0, 2, 2), 90.0, 1e-12);
  // A tilt about x (roll 30 deg) then yaw 45 deg: the heading is still 45 deg. q = qz(45) * qx(30).
  const double cz = std::cos(deg_to_rad(22.5)), sz = std::sin(deg_to_rad(22.5));
  const double cx = std::cos(deg_to_rad(15.0)), sx = std::sin(deg_to_rad(15.0));
  EXPECT_NEAR(*quaternion_yaw_deg(cz * sx, sz * sx, sz * cx, cz * cx), 45.0, 1e-9);
  EXPECT_FALSE(quaternion_yaw_deg(0, 0, 0, 0).has_value());
  EXPECT_FALSE(quaternion_yaw_deg(NAN, 0, 0, 1).has_value());
  // +x pointing straight up (pitch -90 deg): no heading.
  EXPECT_FALSE(quaternion_yaw_deg(0, -std::sqrt(0.5), 0, std::sqrt(0.5)).has_value());
}

TEST(Ros2Convert, PlanarCovarianceInMetresAndRadians) {
  const auto c = planar_covariance(2.0, 0.5);  // 2 cm, 0.5 deg
  EXPECT_DOUBLE_EQ(c[0], 0.0004);              // (0.02 m)^2
  EXPECT_DOUBLE_EQ(c[7], 0.0004);
  EXPECT_NEAR(c[35], std::pow(0.5 * 3.14159265358979 / 180.0, 2), 1e-15);
  for (int i = 0; i < 36; ++i)
    if (i != 0 && i != 7 && i != 35) EXPECT_EQ(c[static_cast<std::size_t>(i)], 0.0) << i;
}

TEST(Ros2Convert, TimeStampsSplitIntoSecondsAndNanoseconds) {
  const RosTime t = ros_time_from_ms(1'764'737'000'123.5);
  EXPECT_EQ(t.sec, 1'764'737'000);
  EXPECT_EQ(t.nanosec, 123'500'000u);
  const RosTime n = ros_time_from_ms(-1.5);  // before the epoch: sec -1, nanosec 998.5 ms
  EXPECT_EQ(n.sec, -1);
  EXPECT_EQ(n.nanosec, 998'500'000u);
}

}  // namespace
}  // namespace omniloc::ros2
