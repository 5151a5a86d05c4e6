// omnilocd's output: the pose datagram's exact text, its round trip through the project's JSON
// reader, delivery over UDP on the loopback interface (never anywhere else), and the status line.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>

#include "omniloc/daemon_publish.hpp"

namespace {

using omniloc::daemon::DaemonStatus;
using omniloc::daemon::PoseMessage;

PoseMessage sample_message() {
  PoseMessage m;
  m.seq = 42;
  m.t_ms = 1234.5;
  m.t_uncertainty_ms = 0.12;
  m.x_cm = 375.125;
  m.y_cm = -2.5;
  m.yaw_deg = 179.75;
  m.source = "integrated";
  m.match_error = 7.25;
  m.search_range_cm = 20;
  m.uncertainty_cm = 1.5;
  m.uncertainty_yaw_deg = 0.25;
  m.vx_cm_s = 120.5;
  m.vy_cm_s = -3.25;
  m.omega_deg_s = 45.0;
  m.mono_ms = 98765.4321;
  m.wall_ms = 1796280000123.5;
  m.status = DaemonStatus::kOk;
  return m;
}

TEST(DaemonPublish, DatagramTextIsExactlyTheDocumentedSchema) {
  EXPECT_EQ(
      omniloc::daemon::pose_json(sample_message()),
      R"({"seq":42,"t_ms":1234.500,"t_uncertainty_ms":0.120,"x_cm":375.125,"y_cm":-2.500,"yaw_deg":179.750,)"
      R"("source":"integrated",)"
      R"("match_error":7.250,"search_range_cm":20.0,"uncertainty_cm":1.500,"uncertainty_yaw_deg":0.250,)"
      R"("vx_cm_s":120.50,"vy_cm_s":-3.25,"omega_deg_s":45.00,"mono_ms":98765.432,"wall_ms":1796280000123.500,)"
      R"("status":"ok"})");
  PoseMessage global = sample_message();  // the last image result came from a global search
  global.search_range_cm.reset();
  EXPECT_NE(
      omniloc::daemon::pose_json(global).find(R"("match_error":7.250,"search_range_cm":-1.0,)"),
      std::string::npos)
      << omniloc::daemon::pose_json(global);
  PoseMessage none = sample_message();
  none.match_error.reset();
  none.search_range_cm.reset();
  none.source = "a\"b";
  none.status = DaemonStatus::kDegraded;
  none.t_uncertainty_ms.reset();  // not a board time: the key is left out
  EXPECT_EQ(
      omniloc::daemon::pose_json(none),
      R"({"seq":42,"t_ms":1234.500,"x_cm":375.125,"y_cm":-2.500,"yaw_deg":179.750,"source":"a\"b",)"
      R"("uncertainty_cm":1.500,"uncertainty_yaw_deg":0.250,"vx_cm_s":120.50,"vy_cm_s":-3.25,"omega_deg_s":45.00,)"
      R"("mono_ms":98765.432,"wall_ms":1796280000123.500,"status":"degraded"})");
  // Issue 37 (hostile input): without a pose from a fix (no board, no fix yet) the datagrams said
  // "uncertainty_cm":0.000, which reads as certain: both keys are left out, as match_error is.
  PoseMessage no_pose = none;
  no_pose.uncertainty_cm.reset();
  no_pose.uncertainty_yaw_deg.reset();
  no_pose.source = "none";
  no_pose.status = DaemonStatus::kNoBoard;
  EXPECT_EQ(
      omniloc::daemon::pose_json(no_pose),
      R"({"seq":42,"t_ms":1234.500,"x_cm":375.125,"y_cm":-2.500,"yaw_deg":179.750,"source":"none",)"
      R"("vx_cm_s":120.50,"vy_cm_s":-3.25,"omega_deg_s":45.00,)"
      R"("mono_ms":98765.432,"wall_ms":1796280000123.500,"status":"no_board"})");
}

TEST(DaemonPublish, StatusNamesAreTheDocumentedOnes) {
  EXPECT_EQ(omniloc::daemon::to_string(DaemonStatus::kStarting), "starting");
  EXPECT_EQ(omniloc::daemon::to_string(DaemonStatus::kOk), "ok");
  EXPECT_EQ(omniloc::daemon::to_string(DaemonStatus::kOdometryOnly), "odometry_only");
  EXPECT_EQ(omniloc::daemon::to_string(DaemonStatus::kLost), "lost");
  EXPECT_EQ(omniloc::daemon::to_string(DaemonStatus::kDegraded), "degraded");
  EXPECT_EQ(omniloc::daemon::to_string(DaemonStatus::kNoBoard), "no_board");
}

// A broadcast destination works (the docs offer one): 127.255.255.255 is the loopback network's
// broadcast address, refused with EACCES unless the socket asks for SO_BROADCAST, and delivered to
// a receiver bound to INADDR_ANY. A failed send keeps its reason for the status line.
TEST(DaemonPublish, BroadcastAddressesAreSentToAndFailuresSayWhy) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  omniloc::daemon::UdpPublisher pub("127.255.255.255", ntohs(a.sin_port));
  pub.send("hello");
  EXPECT_EQ(pub.failed(), 0u) << pub.last_error();
  EXPECT_EQ(pub.sent(), 1u);
  pollfd p{fd, POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 2000), 1);
  char buf[16];
  EXPECT_EQ(::recv(fd, buf, sizeof buf, 0), 5);
  EXPECT_EQ(std::string(buf, 5), "hello");
  ::close(fd);

  // Too big for UDP: the send fails and says why, and the status line shows it.
  pub.send(std::string(70000, 'x'));
  EXPECT_EQ(pub.failed(), 1u);
  EXPECT_EQ(pub.last_error(), "Message too long");
  omniloc::daemon::StatusSnapshot st;
  st.send_failed = pub.failed();
  st.send_error = pub.last_error();
  EXPECT_NE(omniloc::daemon::status_line(st).find("dropped=1 send_error=Message too long"),
            std::string::npos)
      << omniloc::daemon::status_line(st);
}

class LoopbackReceiver {
 public:
  LoopbackReceiver() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = 0;  // ephemeral: tests running in parallel never collide
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return;
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
  }
  ~LoopbackReceiver() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] int port() const { return port_; }
  /// One datagram, waiting at most 2 s; empty on timeout.
  std::string receive() {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 2000) != 1) return {};
    char buf[2048];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  int fd_ = -1;
  int port_ = 0;
};

TEST(DaemonPublish, DatagramsArriveOnLoopbackAndParseBackToTheSameValues) {
  LoopbackReceiver rx;
  ASSERT_GT(rx.port(), 0);
  omniloc::daemon::UdpPublisher pub("127.0.0.1", rx.port());
  for (int i = 0; i < 3; ++i) {
    PoseMessage m = sample_message();
    m.seq = static_cast<std::uint64_t>(100 + i);
    m.x_cm = 10.0 * i + 0.125;
    pub.send(omniloc::daemon::pose_json(m));
  }
  EXPECT_EQ(pub.sent(), 3u);
  EXPECT_EQ(pub.failed(), 0u);
  for (int i = 0; i < 3; ++i) {
    const std::string d = rx.receive();
    ASSERT_FALSE(d.empty()) << "datagram " << i << " did not arrive within 2 s";
    cv::FileStorage fs(
        d, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_JSON);
    EXPECT_EQ(static_cast<int>(fs["seq"].real()), 100 + i);
    EXPECT_EQ(fs["x_cm"].real(), 10.0 * i + 0.125);
    EXPECT_EQ(fs["y_cm"].real(), -2.5);
    EXPECT_EQ(fs["yaw_deg"].real(), 179.75);
    EXPECT_EQ(fs["t_ms"].real(), 1234.5);
    EXPECT_EQ(fs["source"].string(), "integrated");
    EXPECT_EQ(fs["match_error"].real(), 7.25);
    EXPECT_EQ(fs["uncertainty_cm"].real(), 1.5);
    EXPECT_EQ(fs["status"].string(), "ok");
  }
}

TEST(DaemonPublish, BadDestinationIsRefusedWithTheAddress) {
  try {
    omniloc::daemon::UdpPublisher pub("300.1.2.3", 5600);
    FAIL() << "accepted 300.1.2.3";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("300.1.2.3:5600"), std::string::npos) << e.what();
  }
}

TEST(DaemonPublish, StatusLineShowsEveryFigure) {
  omniloc::daemon::StatusSnapshot s;
  s.t_s = 12.04;
  s.status = DaemonStatus::kOdometryOnly;
  s.x_cm = 375.24;
  s.y_cm = 275.06;
  s.yaw_deg = -90.0;
  s.source = "odometry";
  s.match_error.reset();
  s.uncertainty_cm = 3.25;
  s.gyro_drift_deg_per_s = -0.0124;
  s.windows_per_s = 100;
  s.frames_per_s = 0;
  s.published = 1200;
  s.send_failed = 2;
  s.reconnects = 1;
  EXPECT_EQ(omniloc::daemon::status_line(s),
            "t=12.0s odometry_only pose=(375.2,275.1,-90.0) src=odometry err=- sigma=3.2cm "
            "drift=-0.012deg/s win=100/s cam=0/s "
            "sent=1200 dropped=2 reconnects=1");
  s.uncertainty_cm.reset();  // no pose from a fix: no sigma either
  EXPECT_NE(omniloc::daemon::status_line(s).find(" err=- sigma=- drift="), std::string::npos)
      << omniloc::daemon::status_line(s);
}

}  // namespace
