/* ros2_echo: an independent ROS 2 subscriber for the tests, built only from the message IDL
 * (host/ros2/idl/ros2_msgs.idl) and Cyclone DDS's C API; it shares no code with omniloc. It
 * subscribes to rt/omniloc/pose (geometry_msgs/msg/PoseWithCovarianceStamped) and rt/omniloc/odom
 * (nav_msgs/msg/Odometry) with ROS 2's default QoS (reliable, volatile, keep last 10) and prints
 * one line per message:
 *   pose <type> <sec> <nanosec> <frame_id> <x> <y> <z> <qx> <qy> <qz> <qw> <cov0> <cov7> <cov35>
 *   odom <type> <sec> <nanosec> <frame_id> <child_frame_id> <x> <y> <qz> <qw> <vx> <vy> <wz> <twist_cov0>
 * until it has N pose messages or T seconds have passed. With --initialpose X Y YAW_RAD it first
 * publishes one PoseWithCovarianceStamped on rt/initialpose (frame "map"), as RViz's "2D Pose
 * Estimate" does, once a reader has matched.
 * usage: ros2_echo DOMAIN N T [--initialpose X Y YAW_RAD]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <dds/dds.h>

#include "ros2_msgs.h"

static dds_entity_t reader_for(dds_entity_t pp, const dds_topic_descriptor_t* desc, const char* name,
                               const dds_qos_t* qos) {
  dds_entity_t topic = dds_create_topic(pp, desc, name, NULL, NULL);
  if (topic < 0) {
    fprintf(stderr, "ros2_echo: topic %s: %s\n", name, dds_strretcode(topic));
    exit(1);
  }
  dds_entity_t rd = dds_create_reader(pp, topic, qos, NULL);
  if (rd < 0) {
    fprintf(stderr, "ros2_echo: reader %s: %s\n", name, dds_strretcode(rd));
    exit(1);
  }
  return rd;
}

static void publish_initial_pose(dds_entity_t pp, const dds_qos_t* qos, double x, double y, double yaw) {
  dds_entity_t topic =
      dds_create_topic(pp, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, "rt/initialpose", NULL, NULL);
  dds_entity_t wr = dds_create_writer(pp, topic, qos, NULL);
  if (topic < 0 || wr < 0) {
    fprintf(stderr, "ros2_echo: initialpose writer failed\n");
    exit(1);
  }
  /* Wait for the daemon's reader (up to 10 s). */
  dds_set_status_mask(wr, DDS_PUBLICATION_MATCHED_STATUS);
  for (int i = 0; i < 1000; ++i) {
    dds_publication_matched_status_t st;
    dds_get_publication_matched_status(wr, &st);
    if (st.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  geometry_msgs_msg_dds__PoseWithCovarianceStamped_ m;
  memset(&m, 0, sizeof m);
  m.header.frame_id = "map";
  m.pose.pose.position.x = x;
  m.pose.pose.position.y = y;
  m.pose.pose.orientation.z = sin(yaw / 2.0);
  m.pose.pose.orientation.w = cos(yaw / 2.0);
  dds_return_t rc = dds_write(wr, &m);
  printf("sent initialpose %.4f %.4f %.6f %s\n", x, y, yaw, rc == DDS_RETCODE_OK ? "ok" : dds_strretcode(rc));
  fflush(stdout);
}

int main(int argc, char** argv) {
  if (argc != 4 && argc != 8) {
    fprintf(stderr, "usage: ros2_echo DOMAIN N T [--initialpose X Y YAW_RAD]\n");
    return 2;
  }
  const int domain = atoi(argv[1]);
  const int want = atoi(argv[2]);
  const double seconds = atof(argv[3]);
  dds_entity_t pp = dds_create_participant((dds_domainid_t)domain, NULL, NULL);
  if (pp < 0) {
    fprintf(stderr, "ros2_echo: participant: %s\n", dds_strretcode(pp));
    return 1;
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  dds_entity_t pose_rd = reader_for(pp, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, "rt/omniloc/pose", qos);
  dds_entity_t odom_rd = reader_for(pp, &nav_msgs_msg_dds__Odometry__desc, "rt/omniloc/odom", qos);
  if (argc == 8 && strcmp(argv[4], "--initialpose") == 0)
    publish_initial_pose(pp, qos, atof(argv[5]), atof(argv[6]), atof(argv[7]));

  int poses = 0;
  const dds_time_t end = dds_time() + (dds_time_t)(seconds * 1e9);
  while (poses < want && dds_time() < end) {
    void* s[1] = {NULL};
    dds_sample_info_t info;
    int got = 0;
    if (dds_take(pose_rd, s, &info, 1, 1) > 0) {
      got = 1;
      if (info.valid_data) {
        const geometry_msgs_msg_dds__PoseWithCovarianceStamped_* m = s[0];
        const geometry_msgs_msg_dds__Pose_* p = &m->pose.pose;
        printf("pose %s %d %u %s %.6f %.6f %.6f %.9f %.9f %.9f %.9f %.9g %.9g %.9g\n",
               geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc.m_typename, m->header.stamp.sec,
               m->header.stamp.nanosec, m->header.frame_id, p->position.x, p->position.y, p->position.z,
               p->orientation.x, p->orientation.y, p->orientation.z, p->orientation.w, m->pose.covariance[0],
               m->pose.covariance[7], m->pose.covariance[35]);
        ++poses;
      }
      dds_return_loan(pose_rd, s, 1);
    }
    s[0] = NULL;
    if (dds_take(odom_rd, s, &info, 1, 1) > 0) {
      got = 1;
      if (info.valid_data) {
        const nav_msgs_msg_dds__Odometry_* m = s[0];
        printf("odom %s %d %u %s %s %.6f %.6f %.9f %.9f %.6f %.6f %.6f %.9g\n", nav_msgs_msg_dds__Odometry__desc.m_typename,
               m->header.stamp.sec, m->header.stamp.nanosec, m->header.frame_id, m->child_frame_id,
               m->pose.pose.position.x, m->pose.pose.position.y, m->pose.pose.orientation.z,
               m->pose.pose.orientation.w, m->twist.twist.linear.x, m->twist.twist.linear.y,
               m->twist.twist.angular.z, m->twist.covariance[0]);
      }
      dds_return_loan(odom_rd, s, 1);
    }
    if (!got) dds_sleepfor(DDS_MSECS(1));
  }
  fflush(stdout);
  dds_delete_qos(qos);
  dds_delete(pp);
  fprintf(stderr, "ros2_echo: %d pose messages\n", poses);
  return poses >= want ? 0 : 3;
}
