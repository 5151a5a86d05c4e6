// ROS 2 topics without ROS: the daemon's pose published on DDS (Eclipse Cyclone DDS) following
// ROS 2's own conventions, so that `ros2 topic echo /omniloc/pose` on a ROS 2 machine of the same
// network and domain shows it (docs/ROS2.md):
//   /omniloc/pose  geometry_msgs/msg/PoseWithCovarianceStamped  (DDS topic rt/omniloc/pose)
//   /omniloc/odom  nav_msgs/msg/Odometry                        (DDS topic rt/omniloc/odom)
//   /initialpose   geometry_msgs/msg/PoseWithCovarianceStamped  subscribed: a set_pose request
// The message IDL is host/ros2/idl/ros2_msgs.idl. The conversions below are plain functions of the
// robot library; the DDS side (Ros2Bridge) is the library omniloc_ros2, built when Cyclone DDS is
// found (OMNILOC_HAVE_ROS2).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "omniloc/conventions.hpp"

namespace omniloc::ros2 {

/// Where and how to publish. ROS 2 maps ROS_DOMAIN_ID to the DDS domain (0..232).
struct Ros2Config {
  int domain_id = 0;
  std::string topic_prefix = "/omniloc";  ///< the node's namespace: <prefix>/pose, <prefix>/odom
  std::string frame_id = "map";           ///< REP 105: the fixed frame (here the field frame)
  std::string child_frame_id = "base_link";
  std::string initial_pose_topic = "/initialpose";  ///< "" = not subscribed
};

/// ROS 2 topic name -> DDS topic name: "/omniloc/pose" -> "rt/omniloc/pose" (ROS 2's rule for
/// topics: the "rt" prefix, the leading slash kept as the separator). Throws std::invalid_argument
/// for a name ROS 2 would refuse (empty, not absolute, a trailing or double slash, a character
/// other than [A-Za-z0-9_/], a token starting with a digit).
[[nodiscard]] std::string dds_topic_name(const std::string& ros_topic);

/// A yaw (degrees, counter-clockwise about +z) as a unit quaternion (x = y = 0).
struct QuaternionZ {
  double z = 0.0;
  double w = 1.0;
};
[[nodiscard]] QuaternionZ yaw_quaternion(double yaw_deg);
/// The yaw (degrees, wrapped into (-180, 180]) of any quaternion, through its rotation of +x
/// projected on the ground plane; nullopt for a zero or non-finite quaternion.
[[nodiscard]] std::optional<double> quaternion_yaw_deg(double x, double y, double z, double w);

/// A 6 x 6 row-major covariance over (x, y, z, roll, pitch, yaw) in m^2, m rad, rad^2, as ROS 2
/// messages carry it, for a ground robot: sigma_xy_cm is the radial RMS (the datagram's
/// `uncertainty_cm`), so x and y get sigma_xy^2 / 2 each; yaw sigma_yaw_deg; uncorrelated; z, roll
/// and pitch fixed (0) as AMCL reports them.
[[nodiscard]] std::array<double, 36> planar_covariance(double sigma_xy_cm, double sigma_yaw_deg);

/// builtin_interfaces/Time from milliseconds since the Unix epoch (sec may be negative; nanosec
/// always in [0, 1e9)).
struct RosTime {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
};
[[nodiscard]] RosTime ros_time_from_ms(double unix_ms);

/// What one publication carries, in omniloc's units (field frame, cm, deg).
struct Ros2Pose {
  double stamp_unix_ms = 0.0;
  Pose2 pose;
  double sigma_xy_cm = 0.0;
  double sigma_yaw_deg = 0.0;
  double vx_cm_s = 0.0;  ///< velocity in the robot frame (+x forward), as nav_msgs/Odometry's twist
  double vy_cm_s = 0.0;
  double omega_deg_s = 0.0;
};

/// A request to set the pose, from /initialpose (metres and a quaternion turned into cm and deg).
struct InitialPose {
  Pose2 pose;
  std::string frame_id;
};

/// The DDS participant, two writers and a reader. Not copyable; one per daemon.
class Ros2Bridge {
 public:
  /// Throws std::runtime_error naming the domain and topic when DDS cannot be set up, or, in a
  /// build without Cyclone DDS, saying so.
  explicit Ros2Bridge(const Ros2Config& config);
  ~Ros2Bridge();
  Ros2Bridge(const Ros2Bridge&) = delete;
  Ros2Bridge& operator=(const Ros2Bridge&) = delete;

  /// Publishes one pose on both topics; never blocks (a DDS error is counted, not thrown).
  void publish(const Ros2Pose& pose);
  /// The next /initialpose received since the last call, if any (non-blocking).
  [[nodiscard]] std::optional<InitialPose> take_initial_pose();

  [[nodiscard]] std::uint64_t published() const;
  [[nodiscard]] std::uint64_t failed() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// True in a build with Cyclone DDS (Ros2Bridge works), false otherwise.
[[nodiscard]] bool ros2_available();

}  // namespace omniloc::ros2
