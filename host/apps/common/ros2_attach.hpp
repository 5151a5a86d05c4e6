// The daemon's ROS 2 topics (docs/ROS2.md), shared by omnilocd and omnilocd-sim: with
// `ros2_domain_id` >= 0 a Ros2Bridge publishes every pose the daemon sends as a datagram, from the
// daemon's own observer callbacks (so the UDP stream and the topics carry the same poses).
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "omniloc/daemon.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/log.hpp"
#include "omniloc/ros2_bridge.hpp"

namespace omniloc::cli {

class Ros2Attachment {
 public:
  /// Nothing when config.ros2_domain_id < 0; else the bridge, or std::runtime_error saying why not.
  Ros2Attachment(const daemon::DaemonConfig& config, const Logger& log) : log_(log) {
    if (config.ros2_domain_id < 0) return;
    ros2::Ros2Config rc;
    rc.domain_id = config.ros2_domain_id;
    rc.topic_prefix = config.ros2_namespace;
    rc.frame_id = config.ros2_frame_id;
    bridge_ = std::make_unique<ros2::Ros2Bridge>(rc);
    frame_id_ = rc.frame_id;
    log_.info("ROS 2 topics " + rc.topic_prefix + "/pose, " + rc.topic_prefix +
              "/odom (subscribed: " + rc.initial_pose_topic + ") in DDS domain " +
              std::to_string(rc.domain_id));
  }

  /// Chains the publication onto `observer`'s on_pose and the /initialpose subscription onto its
  /// on_loop (any callbacks there still run first). An /initialpose in the poses' frame (or with no
  /// frame) becomes a control-channel set_pose on `daemon`; others are refused in the log.
  void attach(daemon::DaemonObserver& observer, daemon::Daemon& daemon) {
    if (!bridge_) return;
    observer.on_loop = [this, &daemon, next = std::move(observer.on_loop)](double now_ms) {
      if (next) next(now_ms);
      const auto ip = bridge_->take_initial_pose();
      if (!ip) return;
      if (!ip->frame_id.empty() && ip->frame_id != frame_id_) {
        log_.warning("ROS 2: /initialpose in frame '" + ip->frame_id + "' ignored (poses are in '" +
                     frame_id_ + "')");
        return;
      }
      try {
        (void)daemon.apply(control::SetPose{ip->pose.x_cm, ip->pose.y_cm, ip->pose.yaw_deg});
      } catch (const control::ControlError& e) {
        log_.warning(std::string("ROS 2: /initialpose refused: ") + e.what());
      }
    };
    observer.on_pose = [bridge = bridge_.get(),
                        next = std::move(observer.on_pose)](const daemon::PoseEvent& e) {
      if (next) next(e);
      if (e.message.status == daemon::DaemonStatus::kNoBoard ||
          e.message.status == daemon::DaemonStatus::kStarting || !e.message.uncertainty_cm ||
          !e.message.uncertainty_yaw_deg)
        return;  // no pose yet: nothing to put on a pose topic
      ros2::Ros2Pose p;
      p.stamp_unix_ms = e.message.wall_ms;
      p.pose = Pose2{e.message.x_cm, e.message.y_cm, e.message.yaw_deg};
      p.sigma_xy_cm = *e.message.uncertainty_cm;
      p.sigma_yaw_deg = *e.message.uncertainty_yaw_deg;
      p.vx_cm_s = e.message.vx_cm_s;
      p.vy_cm_s = e.message.vy_cm_s;
      p.omega_deg_s = e.message.omega_deg_s;
      bridge->publish(p);
    };
  }

  [[nodiscard]] ros2::Ros2Bridge* bridge() { return bridge_.get(); }

 private:
  std::unique_ptr<ros2::Ros2Bridge> bridge_;
  std::string frame_id_;
  Logger log_;
};

}  // namespace omniloc::cli
