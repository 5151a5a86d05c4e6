// Ros2Bridge on Eclipse Cyclone DDS's C API: one participant in the configured domain, a writer
// per published topic and a reader for /initialpose, with the QoS `ros2 topic echo` and RViz use by
// default (reliable, volatile, keep last 10).
#include <cstring>
#include <stdexcept>

#include <dds/dds.h>

#include "omniloc/ros2_bridge.hpp"
#include "ros2_msgs.h"

namespace omniloc::ros2 {

namespace {

std::string dds_error(const char* what, dds_return_t rc) {
  return std::string(what) + ": " + dds_strretcode(rc);
}

void fill_pose(geometry_msgs_msg_dds__PoseWithCovariance_& out, const Ros2Pose& p) {
  out.pose.position.x = p.pose.x_cm / 100.0;
  out.pose.position.y = p.pose.y_cm / 100.0;
  out.pose.position.z = 0.0;
  const QuaternionZ q = yaw_quaternion(p.pose.yaw_deg);
  out.pose.orientation = {0.0, 0.0, q.z, q.w};
  const auto cov = planar_covariance(p.sigma_xy_cm, p.sigma_yaw_deg);
  std::memcpy(out.covariance, cov.data(), sizeof out.covariance);
}

}  // namespace

struct Ros2Bridge::Impl {
  Ros2Config config;
  std::string frame_id, child_frame_id;  // the char* in the samples point here
  dds_entity_t participant = 0;
  dds_entity_t pose_writer = 0;
  dds_entity_t odom_writer = 0;
  dds_entity_t initial_reader = 0;
  std::uint64_t published = 0;
  std::uint64_t failed = 0;

  ~Impl() {
    if (participant > 0) dds_delete(participant);  // deletes its topics, writers and readers
  }

  dds_entity_t topic(const dds_topic_descriptor_t* type, const std::string& ros_name) {
    const std::string name = dds_topic_name(ros_name);
    const dds_entity_t t = dds_create_topic(participant, type, name.c_str(), nullptr, nullptr);
    if (t < 0) throw std::runtime_error(dds_error(("ROS 2: topic " + name).c_str(), t));
    return t;
  }
};

Ros2Bridge::Ros2Bridge(const Ros2Config& config) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.config = config;
  m.frame_id = config.frame_id;
  m.child_frame_id = config.child_frame_id;
  if (config.domain_id < 0 || config.domain_id > 232)
    throw std::runtime_error("ROS 2: domain id must be in [0, 232] (got " +
                             std::to_string(config.domain_id) + ")");
  m.participant =
      dds_create_participant(static_cast<dds_domainid_t>(config.domain_id), nullptr, nullptr);
  if (m.participant < 0)
    throw std::runtime_error(
        dds_error(("ROS 2: DDS participant in domain " + std::to_string(config.domain_id)).c_str(),
                  m.participant));
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  try {
    const dds_entity_t pose_topic = m.topic(&geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc,
                                            config.topic_prefix + "/pose");
    const dds_entity_t odom_topic =
        m.topic(&nav_msgs_msg_dds__Odometry__desc, config.topic_prefix + "/odom");
    m.pose_writer = dds_create_writer(m.participant, pose_topic, qos, nullptr);
    m.odom_writer = dds_create_writer(m.participant, odom_topic, qos, nullptr);
    if (m.pose_writer < 0 || m.odom_writer < 0)
      throw std::runtime_error(
          dds_error("ROS 2: writer", m.pose_writer < 0 ? m.pose_writer : m.odom_writer));
    if (!config.initial_pose_topic.empty()) {
      const dds_entity_t init_topic = m.topic(
          &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, config.initial_pose_topic);
      m.initial_reader = dds_create_reader(m.participant, init_topic, qos, nullptr);
      if (m.initial_reader < 0)
        throw std::runtime_error(dds_error("ROS 2: reader", m.initial_reader));
    }
  } catch (...) {
    dds_delete_qos(qos);
    throw;
  }
  dds_delete_qos(qos);
}

Ros2Bridge::~Ros2Bridge() = default;

void Ros2Bridge::publish(const Ros2Pose& p) {
  Impl& m = *impl_;
  const RosTime stamp = ros_time_from_ms(p.stamp_unix_ms);
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ pose{};
  pose.header.stamp = {stamp.sec, stamp.nanosec};
  pose.header.frame_id = m.frame_id.data();
  fill_pose(pose.pose, p);
  nav_msgs_msg_dds__Odometry_ odom{};
  odom.header = pose.header;
  odom.child_frame_id = m.child_frame_id.data();
  odom.pose = pose.pose;
  odom.twist.twist.linear = {p.vx_cm_s / 100.0, p.vy_cm_s / 100.0, 0.0};
  odom.twist.twist.angular = {0.0, 0.0, deg_to_rad(p.omega_deg_s)};
  // No estimate of the velocity's uncertainty yet: ROS's convention for "unknown" is -1 in the
  // first element.
  odom.twist.covariance[0] = -1.0;
  const dds_return_t a = dds_write(m.pose_writer, &pose);
  const dds_return_t b = dds_write(m.odom_writer, &odom);
  if (a == DDS_RETCODE_OK && b == DDS_RETCODE_OK)
    ++m.published;
  else
    ++m.failed;
}

std::optional<InitialPose> Ros2Bridge::take_initial_pose() {
  Impl& m = *impl_;
  if (m.initial_reader <= 0) return std::nullopt;
  std::optional<InitialPose> latest;
  for (;;) {
    void* samples[1] = {nullptr};
    dds_sample_info_t info;
    const dds_return_t n = dds_take(m.initial_reader, samples, &info, 1, 1);
    if (n <= 0) break;
    if (info.valid_data) {
      const auto* s =
          static_cast<const geometry_msgs_msg_dds__PoseWithCovarianceStamped_*>(samples[0]);
      const auto& q = s->pose.pose.orientation;
      const auto yaw = quaternion_yaw_deg(q.x, q.y, q.z, q.w);
      const auto& pos = s->pose.pose.position;
      if (yaw && std::isfinite(pos.x) && std::isfinite(pos.y))
        latest = InitialPose{Pose2{pos.x * 100.0, pos.y * 100.0, *yaw},
                             s->header.frame_id != nullptr ? s->header.frame_id : ""};
    }
    dds_return_loan(m.initial_reader, samples, n);
  }
  return latest;
}

std::uint64_t Ros2Bridge::published() const {
  return impl_->published;
}
std::uint64_t Ros2Bridge::failed() const {
  return impl_->failed;
}

bool ros2_available() {
  return true;
}

}  // namespace omniloc::ros2
