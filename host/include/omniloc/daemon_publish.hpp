// What omnilocd sends: one JSON object per UDP datagram per board window (100 Hz), and the status
// line it prints once a second. Schema: docs/DAEMON.md ("UDP pose datagrams").
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace omniloc::daemon {

/// The daemon's health, most severe last.
enum class DaemonStatus {
  kStarting,      ///< no pose yet (before the first global search succeeded)
  kOk,            ///< board and camera delivering, pose from the localizer
  kOdometryOnly,  ///< the camera stopped delivering: the pose is dead reckoning, flagged
  kLost,          ///< the localizer does not know where it is (searching globally)
  kDegraded,      ///< the board is gone (unplugged): pose frozen at the last estimate, reconnecting
  kNoBoard,  ///< no board since start-up: no pose at all (zeros, source none), trying to connect
};

[[nodiscard]] std::string_view to_string(DaemonStatus status);

/// One published pose.
struct PoseMessage {
  std::uint64_t seq = 0;  ///< datagram counter (gaps at the receiver = lost datagrams)
  double t_ms = 0.0;      ///< daemon time of the pose (board time of the encoder window)
  std::optional<double> t_uncertainty_ms;  ///< 1-sigma of t_ms from the board-clock fit; none: no
                                           ///< board window (key omitted)
  double x_cm = 0.0;
  double y_cm = 0.0;
  double yaw_deg = 0.0;
  std::string source;  ///< the localizer's source of this pose ("image", "odometry", ...)
  /// Normalised match error of the last image result used; none: no image result (key omitted).
  std::optional<double> match_error;
  /// Search range of that image result; none: a global search (sent as -1 beside a match_error).
  std::optional<double> search_range_cm;
  /// 1-sigma position and heading uncertainty of the pose; none when the pose is not the
  /// localizer's (source "none": no board, no fix yet), keys omitted: never 0, which reads as
  /// certain.
  std::optional<double> uncertainty_cm;
  std::optional<double> uncertainty_yaw_deg;
  double vx_cm_s = 0.0;  ///< robot-frame velocity (+x forward, +y left) from the odometry
  double vy_cm_s = 0.0;
  double omega_deg_s = 0.0;  ///< yaw rate, counter-clockwise positive
  double mono_ms = 0.0;      ///< CLOCK_MONOTONIC (steady_clock) of the host when sent, ms
  double wall_ms = 0.0;      ///< the host's wall clock (Unix time) when sent, ms
  DaemonStatus status = DaemonStatus::kStarting;
};

/// The datagram: a single-line JSON object, keys in the order of PoseMessage. Optional values that
/// are "none" are left out; a non-finite number (never expected) is written as null (JSON has no
/// NaN).
[[nodiscard]] std::string pose_json(const PoseMessage& message);

/// Sends datagrams to one IPv4 address and port. Sending never blocks the daemon: a full socket
/// buffer or an unreachable consumer drops the datagram and counts it.
class UdpPublisher {
 public:
  /// Throws std::runtime_error naming the address when the socket cannot be made.
  UdpPublisher(const std::string& ipv4_address, int port);
  ~UdpPublisher();
  UdpPublisher(const UdpPublisher&) = delete;
  UdpPublisher& operator=(const UdpPublisher&) = delete;

  void send(std::string_view datagram);
  [[nodiscard]] std::uint64_t sent() const { return sent_; }
  [[nodiscard]] std::uint64_t failed() const { return failed_; }
  /// Why the last failed send failed (strerror), empty before any failure.
  [[nodiscard]] const std::string& last_error() const { return last_error_; }

 private:
  int fd_ = -1;
  std::uint64_t sent_ = 0;
  std::uint64_t failed_ = 0;
  std::string last_error_;
  unsigned char addr_[16] =
      {};  // sockaddr_in, kept opaque to keep <netinet/in.h> out of the header
};

/// Everything the once-a-second status line shows.
struct StatusSnapshot {
  double t_s = 0.0;
  DaemonStatus status = DaemonStatus::kStarting;
  double x_cm = 0.0, y_cm = 0.0, yaw_deg = 0.0;
  std::string source;
  std::optional<double> match_error;     ///< none: no image result ("err=-")
  std::optional<double> uncertainty_cm;  ///< none: no pose from a fix ("sigma=-")
  double gyro_drift_deg_per_s = 0.0;     ///< drift correction the localizer learnt from the images
  double windows_per_s = 0.0;            ///< encoder windows received over the last period
  double frames_per_s = 0.0;             ///< camera frames used over the last period
  std::uint64_t published = 0;
  std::uint64_t send_failed = 0;
  std::string send_error;  ///< why the last failed send failed (shown when sends fail)
  std::uint64_t reconnects = 0;
  std::string recording;  ///< "" (none), "on" or "stopped" (a write failed: disk full...)
  std::uint64_t recording_failures = 0;  ///< write errors that stopped the recording
};

/// One line, no newline, e.g.
/// "t=12.0s ok pose=(375.2,275.1,90.0) src=integrated err=3.1 sigma=1.2cm drift=+0.004deg/s
/// win=100/s cam=60/s sent=1200".
[[nodiscard]] std::string status_line(const StatusSnapshot& s);

}  // namespace omniloc::daemon
