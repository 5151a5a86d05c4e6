// The daemon's ROS 2 topics as a ROS 2 machine sees them: omnilocd-sim publishes, ros2_echo (built
// from the IDL and Cyclone DDS's C API only) subscribes with ROS 2's default QoS. What it receives
// is checked against the daemon's other, independent output, the UDP datagrams of the same run.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "temp_dir.hpp"
#include "udp_receiver.hpp"

namespace fs = std::filesystem;

namespace {

// Discovery on loopback by unicast only: the test does not depend on the machine's network (CI
// containers, firewalls) and cannot disturb a real robot on the LAN.
constexpr const char* kLoopbackDds =
    "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface "
    "name=\"lo\"/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</"
    "ParticipantIndex>"
    "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>";

using omniloc::test::TempDir;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::vector<std::vector<std::string>> lines_of(const std::string& text, const std::string& kind) {
  std::vector<std::vector<std::string>> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::istringstream ls(line);
    std::vector<std::string> f;
    for (std::string w; ls >> w;) f.push_back(w);
    if (!f.empty() && f[0] == kind) out.push_back(f);
  }
  return out;
}

double yaw_of(double qz, double qw) {
  return std::atan2(2.0 * qz * qw, qw * qw - qz * qz) * 180.0 / M_PI;
}

double yaw_gap(double a, double b) {
  return std::fabs(std::remainder(a - b, 360.0));
}

TEST(Ros2Topics, ASubscriberBuiltFromTheIdlReceivesTheDatagramsPoses) {
  TempDir dir("ros2");
  ::setenv("CYCLONEDDS_URI", kLoopbackDds, 1);
  const int domain = 150 + ::getpid() % 80;  // apart from other runs of this test on the machine
  omniloc::test::UdpReceiver rx;
  ASSERT_NE(rx.port(), 0);
  const std::string cmd =
      "( " + std::string(ROS2_ECHO_PATH) + " " + std::to_string(domain) + " 150 20 >" +
      (dir.path / "echo.txt").string() + " 2>" + (dir.path / "echo.err").string() + " & " +
      std::string(OMNILOCD_SIM_PATH) + " --duration-s 3 --status-period-s 0 --udp-port " +
      std::to_string(rx.port()) + " --ros2-domain-id " + std::to_string(domain) + " >" +
      (dir.path / "daemon.log").string() + " 2>&1; echo daemon $? >" +
      (dir.path / "rc.txt").string() + "; wait )";
  const double start_s =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const double now_s =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  ASSERT_EQ(slurp(dir.path / "rc.txt"), "daemon 0\n") << slurp(dir.path / "daemon.log");

  std::vector<nlohmann::json> grams;
  for (const std::string& g : rx.drain()) {
    nlohmann::json j = nlohmann::json::parse(g);
    if (j["status"] != "starting" && j["status"] != "no_board") grams.push_back(std::move(j));
  }
  const std::string echo = slurp(dir.path / "echo.txt");
  const auto poses = lines_of(echo, "pose");
  const auto odoms = lines_of(echo, "odom");
  std::printf(
      "%zu datagrams with a pose; ros2_echo got %zu pose and %zu odom messages; first:\n  %s\n",
      grams.size(), poses.size(), odoms.size(), echo.substr(0, echo.find('\n')).c_str());
  ASSERT_GE(poses.size(), 150u) << slurp(dir.path / "echo.err") << slurp(dir.path / "daemon.log");
  ASSERT_GE(odoms.size(), 140u);

  // The first message received is some datagram (discovery takes a moment: volatile topics drop
  // what was sent before the subscriber matched); from there on, message i is datagram k + i.
  const auto x_of = [](const std::vector<std::string>& f, int i) {
    return std::stod(f[static_cast<std::size_t>(i)]);
  };
  std::size_t k = 0;
  while (k < grams.size() &&
         !(std::fabs(grams[k]["x_cm"].get<double>() - 100.0 * x_of(poses[0], 5)) < 0.01 &&
           std::fabs(grams[k]["y_cm"].get<double>() - 100.0 * x_of(poses[0], 6)) < 0.01))
    ++k;
  ASSERT_LT(k, grams.size()) << "the first pose message matches no datagram";
  int prev_sec = 0;
  unsigned prev_ns = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto& f = poses[i];
    ASSERT_LT(k + i, grams.size());
    const nlohmann::json& g = grams[k + i];
    ASSERT_EQ(f.size(), 15u);
    EXPECT_EQ(f[1], "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_");
    EXPECT_EQ(f[4], "map");
    EXPECT_NEAR(100.0 * x_of(f, 5), g["x_cm"].get<double>(), 0.01) << "message " << i;
    EXPECT_NEAR(100.0 * x_of(f, 6), g["y_cm"].get<double>(), 0.01) << "message " << i;
    EXPECT_EQ(x_of(f, 7), 0.0);
    EXPECT_EQ(x_of(f, 8), 0.0);
    EXPECT_EQ(x_of(f, 9), 0.0);
    EXPECT_LT(yaw_gap(yaw_of(x_of(f, 10), x_of(f, 11)), g["yaw_deg"].get<double>()), 0.01)
        << "message " << i;
    EXPECT_NEAR(std::hypot(x_of(f, 10), x_of(f, 11)), 1.0, 1e-9);
    const double sigma_m = g["uncertainty_cm"].get<double>() / 100.0;
    const double sigma_rad = g["uncertainty_yaw_deg"].get<double>() * M_PI / 180.0;
    // The datagram's uncertainty is the radial RMS: each axis carries half its square. The datagram
    // keeps 3 decimals of the sigmas (cm, deg), the message their full value: a variance differs by
    // up to 2 sigma x the rounding.
    const double tol_m2 = 2.0 * sigma_m * 0.5e-5 + 1e-10;
    const double tol_rad2 = 2.0 * sigma_rad * (0.5e-3 * M_PI / 180.0) + 1e-10;
    EXPECT_NEAR(x_of(f, 12), sigma_m * sigma_m / 2.0, tol_m2);
    EXPECT_NEAR(x_of(f, 13), sigma_m * sigma_m / 2.0, tol_m2);
    EXPECT_NEAR(x_of(f, 14), sigma_rad * sigma_rad, tol_rad2);
    const int sec = std::stoi(f[2]);
    const unsigned ns = static_cast<unsigned>(std::stoul(f[3]));
    EXPECT_LT(ns, 1'000'000'000u);
    EXPECT_TRUE(sec > prev_sec || (sec == prev_sec && ns >= prev_ns)) << "stamps go forward";
    // A wall-clock stamp: taken between the start of the run and its end.
    EXPECT_GE(sec + ns * 1e-9, start_s - 1.0);
    EXPECT_LE(sec + ns * 1e-9, now_s + 1.0);
    prev_sec = sec;
    prev_ns = ns;
  }
  for (const auto& f : odoms) {
    ASSERT_EQ(f.size(), 14u);
    EXPECT_EQ(f[1], "nav_msgs::msg::dds_::Odometry_");
    EXPECT_EQ(f[4], "map");
    EXPECT_EQ(f[5], "base_link");
    EXPECT_EQ(x_of(f, 13), -1.0) << "twist covariance unknown: -1 (ROS convention)";
  }
  // The stamp is the datagram's wall_ms and the twist its velocity (m/s, rad/s, robot frame).
  std::size_t twists = 0;
  for (const auto& o : odoms)
    for (const auto& g : grams) {
      const double wall_s = g["wall_ms"].get<double>() / 1000.0;
      if (std::fabs(std::stoi(o[2]) + std::stoul(o[3]) * 1e-9 - wall_s) > 1e-6) continue;
      EXPECT_NEAR(100.0 * x_of(o, 10), g["vx_cm_s"].get<double>(), 0.01);
      EXPECT_NEAR(100.0 * x_of(o, 11), g["vy_cm_s"].get<double>(), 0.01);
      EXPECT_NEAR(x_of(o, 12) * 180.0 / M_PI, g["omega_deg_s"].get<double>(), 0.01);
      ++twists;
      break;
    }
  std::printf("%zu odometry messages matched to their datagram by stamp, twist equal\n", twists);
  EXPECT_GE(twists, odoms.size() * 9 / 10);
  // An odometry message carries the same pose as the pose message of the same datagram.
  bool found = false;
  for (const auto& o : odoms)
    for (const auto& p : poses)
      if (o[2] == p[2] && o[3] == p[3]) {
        EXPECT_EQ(o[6], p[5]);
        EXPECT_EQ(o[7], p[6]);
        found = true;
      }
  EXPECT_TRUE(found) << "no odometry message with a pose message's stamp";
}

// RViz's "2D Pose Estimate" publishes /initialpose: the daemon takes it as a set_pose, so the pose
// stream jumps to it (metres and a quaternion turned into cm and deg).
TEST(Ros2Topics, AnInitialPoseMovesThePublishedPose) {
  TempDir dir("ros2_init");
  ::setenv("CYCLONEDDS_URI", kLoopbackDds, 1);
  const int domain = 150 + (::getpid() + 40) % 80;
  omniloc::test::UdpReceiver rx;
  ASSERT_NE(rx.port(), 0);
  const std::string cmd =
      "( " + std::string(OMNILOCD_SIM_PATH) + " --duration-s 4 --status-period-s 0 --udp-port " +
      std::to_string(rx.port()) + " --ros2-domain-id " + std::to_string(domain) + " >" +
      (dir.path / "daemon.log").string() + " 2>&1 & sleep 1; " + std::string(ROS2_ECHO_PATH) + " " +
      std::to_string(domain) + " 5 20 --initialpose 2.0 1.5 0.5235987755982988 >" +
      (dir.path / "echo.txt").string() + " 2>&1; wait )";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir.path / "echo.txt");
  ASSERT_NE(slurp(dir.path / "echo.txt").find("sent initialpose 2.0000 1.5000 0.523599 ok"),
            std::string::npos)
      << slurp(dir.path / "echo.txt");
  std::vector<nlohmann::json> grams;
  for (const std::string& g : rx.drain()) grams.push_back(nlohmann::json::parse(g));
  std::size_t jump = 0;
  for (std::size_t i = 1; i < grams.size() && jump == 0; ++i) {
    const auto d = [&](std::size_t k) {
      return std::hypot(grams[k]["x_cm"].get<double>() - 200.0,
                        grams[k]["y_cm"].get<double>() - 150.0);
    };
    if (d(i) < 3.0 && d(i - 1) > 50.0) jump = i;
  }
  ASSERT_GT(jump, 0u) << "no datagram jumped to (200, 150) cm; log:\n"
                      << slurp(dir.path / "daemon.log");
  std::printf("datagram %zu after /initialpose: %s\n", jump, grams[jump].dump().c_str());
  EXPECT_LT(yaw_gap(grams[jump]["yaw_deg"].get<double>(), 30.0), 1.0);
  EXPECT_NE(slurp(dir.path / "daemon.log").find("pose set by command to (200.0, 150.0) cm"),
            std::string::npos);
}

TEST(Ros2Topics, AnUnusableDomainIsRefusedByName) {
  TempDir dir("ros2_bad");
  const std::string cmd = std::string(OMNILOCD_SIM_PATH) +
                          " --duration-s 1 --ros2-domain-id 233 >" + (dir.path / "log").string() +
                          " 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string log = slurp(dir.path / "log");
  EXPECT_NE(log.find("ros2_domain_id"), std::string::npos) << log;
  EXPECT_NE(log.find("233"), std::string::npos) << log;
}

}  // namespace
