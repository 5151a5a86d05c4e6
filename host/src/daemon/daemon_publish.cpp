// UDP pose datagrams and the status line of omnilocd.
#include "omniloc/daemon_publish.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace omniloc::daemon {

std::string_view to_string(DaemonStatus status) {
  switch (status) {
    case DaemonStatus::kStarting:
      return "starting";
    case DaemonStatus::kOk:
      return "ok";
    case DaemonStatus::kOdometryOnly:
      return "odometry_only";
    case DaemonStatus::kLost:
      return "lost";
    case DaemonStatus::kDegraded:
      return "degraded";
    case DaemonStatus::kNoBoard:
      return "no_board";
  }
  return "unknown";
}

namespace {

// %.17g would round-trip but bloats every datagram; 0.001 cm / 1 us resolution is far below noise.
void put_number(std::string& out, double v, int decimals) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  out += buf;
}

void put_string(std::string& out, std::string_view s) {
  out += '"';
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x",
                    static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += buf;
    } else {
      out += c;
    }
  }
  out += '"';
}

}  // namespace

std::string pose_json(const PoseMessage& m) {
  std::string out;
  out.reserve(256);
  out += "{\"seq\":";
  out += std::to_string(m.seq);
  out += ",\"t_ms\":";
  put_number(out, m.t_ms, 3);
  if (m.t_uncertainty_ms) {
    out += ",\"t_uncertainty_ms\":";
    put_number(out, *m.t_uncertainty_ms, 3);
  }
  out += ",\"x_cm\":";
  put_number(out, m.x_cm, 3);
  out += ",\"y_cm\":";
  put_number(out, m.y_cm, 3);
  out += ",\"yaw_deg\":";
  put_number(out, m.yaw_deg, 3);
  out += ",\"source\":";
  put_string(out, m.source);
  // Absent rather than null: every key present is a number (docs/DAEMON.md). The two come together:
  // a search range of -1 says the last image result came from a global search.
  if (m.match_error) {
    out += ",\"match_error\":";
    put_number(out, *m.match_error, 3);
    out += ",\"search_range_cm\":";
    put_number(out, m.search_range_cm.value_or(-1.0), 1);
  }
  // Absent too without a pose from a fix: 0 would read as certain.
  if (m.uncertainty_cm) {
    out += ",\"uncertainty_cm\":";
    put_number(out, *m.uncertainty_cm, 3);
  }
  if (m.uncertainty_yaw_deg) {
    out += ",\"uncertainty_yaw_deg\":";
    put_number(out, *m.uncertainty_yaw_deg, 3);
  }
  out += ",\"vx_cm_s\":";
  put_number(out, m.vx_cm_s, 2);
  out += ",\"vy_cm_s\":";
  put_number(out, m.vy_cm_s, 2);
  out += ",\"omega_deg_s\":";
  put_number(out, m.omega_deg_s, 2);
  out += ",\"mono_ms\":";
  put_number(out, m.mono_ms, 3);
  out += ",\"wall_ms\":";
  put_number(out, m.wall_ms, 3);
  out += ",\"status\":";
  put_string(out, to_string(m.status));
  out += '}';
  return out;
}

UdpPublisher::UdpPublisher(const std::string& ipv4_address, int port) {
  static_assert(sizeof(sockaddr_in) <= sizeof(addr_));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (port < 1 || port > 65535 || inet_pton(AF_INET, ipv4_address.c_str(), &a.sin_addr) != 1)
    throw std::runtime_error("UDP publisher: bad destination " + ipv4_address + ":" +
                             std::to_string(port));
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0)
    throw std::runtime_error("UDP publisher for " + ipv4_address + ":" + std::to_string(port) +
                             ": socket() failed: " + std::strerror(errno));
  // Broadcast destinations (192.168.1.255, 255.255.255.255) are refused with EACCES unless asked
  // for.
  const int on = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_BROADCAST, &on, sizeof on) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    throw std::runtime_error("UDP publisher for " + ipv4_address + ":" + std::to_string(port) +
                             ": SO_BROADCAST failed: " + why);
  }
  std::memcpy(addr_, &a, sizeof a);
}

UdpPublisher::~UdpPublisher() {
  if (fd_ >= 0) ::close(fd_);
}

void UdpPublisher::send(std::string_view datagram) {
  const ssize_t n = ::sendto(fd_, datagram.data(), datagram.size(), 0,
                             reinterpret_cast<const sockaddr*>(addr_), sizeof(sockaddr_in));
  // ECONNREFUSED (nobody listening yet) and EAGAIN are normal for a fire-and-forget stream.
  if (n == static_cast<ssize_t>(datagram.size())) {
    ++sent_;
  } else {
    ++failed_;
    last_error_ = n < 0 ? std::strerror(errno) : "short send";
  }
}

std::string status_line(const StatusSnapshot& s) {
  char buf[448];
  char err[32];
  if (s.match_error)
    std::snprintf(err, sizeof err, "%.1f", *s.match_error);
  else
    std::snprintf(err, sizeof err, "-");
  char sigma[32];
  if (s.uncertainty_cm)
    std::snprintf(sigma, sizeof sigma, "%.1fcm", *s.uncertainty_cm);
  else
    std::snprintf(sigma, sizeof sigma, "-");
  std::snprintf(
      buf, sizeof buf,
      "t=%.1fs %s pose=(%.1f,%.1f,%.1f) src=%s err=%s sigma=%s drift=%+.3fdeg/s win=%.0f/s "
      "cam=%.0f/s "
      "sent=%llu dropped=%llu%s%s reconnects=%llu",
      s.t_s, std::string(to_string(s.status)).c_str(), s.x_cm, s.y_cm, s.yaw_deg,
      s.source.empty() ? "-" : s.source.c_str(), err, sigma, s.gyro_drift_deg_per_s,
      s.windows_per_s, s.frames_per_s, static_cast<unsigned long long>(s.published),
      static_cast<unsigned long long>(s.send_failed),
      s.send_failed > 0 && !s.send_error.empty() ? " send_error=" : "",
      s.send_failed > 0 ? s.send_error.c_str() : "", static_cast<unsigned long long>(s.reconnects));
  std::string line = buf;
  if (!s.recording.empty())
    line += " rec=" + s.recording + " rec_failures=" + std::to_string(s.recording_failures);
  return line;
}

}  // namespace omniloc::daemon
