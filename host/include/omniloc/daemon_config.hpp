// Configuration of the robot daemon `omnilocd`: a JSON file (common/omnilocd/default.json, read by
// the config layer, config_reader.hpp) whose values command-line flags override. Every key is
// optional, unknown and duplicate keys are refused (a misspelt key must not fall back to its
// default silently), and every value is checked; errors name the file (or "command line") and the
// field. Keys, defaults and units: docs/DAEMON.md.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "omniloc/config.hpp"  // ConfigError

namespace omniloc::daemon {

/// The member initialisers are the shipped defaults: a test checks they equal every key of
/// common/omnilocd/default.json.
struct DaemonConfig {
  // --- board (FT2232H over libusb) ---
  std::string board_serial;          ///< the board's serial, empty for the first one found
  double reconnect_period_ms = 500;  ///< time between reopen attempts after an unplug
  // --- camera ---
  std::string camera = "0";        ///< "none", a V4L2 index ("0"), a device path or a video file
  double camera_fps = 60.0;        ///< requested rate (a video file: its pacing)
  double camera_timeout_ms = 500;  ///< no frame for this long: odometry only, flagged
  /// Exposure to hand-over of a frame with no driver timestamp: subtracted from the hand-over time
  /// (docs/DAEMON.md "Camera time"). 33 ms: two 60 Hz frame periods.
  double camera_latency_ms = 33;
  // --- models ---
  std::string field = "fira-robosot";    ///< common/fields/<name>.json or a path
  std::string camera_model = "default";  ///< common/cameras/<name>.json or a path
  std::string robot = "default";         ///< common/robots/<name>.json or a path
  std::string localizer = "default";     ///< common/localizer/<name>.json or a path
  std::string database;                  ///< feature DB file; empty: built in memory at start-up
  double grid_step_cm = 10.0;            ///< grid of a database built at start-up
  std::string side = "unknown";  ///< the defended goal's colour: "blue", "yellow" or "unknown"
                                 ///< (Localizer::set_side)
  // --- output ---
  std::string udp_address = "127.0.0.1";  ///< IPv4 address of the pose consumer
  int udp_port = 5600;
  int control_port = 5601;        ///< control channel (control.hpp) on 127.0.0.1; 0: off
  double publish_hz = 100.0;      ///< one datagram per board window; checked to be the window rate
  std::string record_dir;         ///< empty: no recording
  bool record_overwrite = false;  ///< replace an old recording in record_dir (else refused)
  std::string record_format = "jpeg";  ///< frame store: "jpeg" (compact) or "png" (lossless)
  double status_period_s = 1.0;        ///< status line on stderr; 0 disables it
  std::string log_level = "info";  ///< error | warning | info | debug (log.hpp); -v / -q move it
  double duration_s = 0.0;         ///< stop after this much (daemon) time; 0: until SIGINT/SIGTERM
  // --- ROS 2 topics (docs/ROS2.md; needs a build with Cyclone DDS) ---
  int ros2_domain_id = -1;  ///< DDS domain (ROS_DOMAIN_ID) of the topics; -1: no ROS 2
  std::string ros2_namespace = "/omniloc";  ///< topics <ns>/pose and <ns>/odom
  std::string ros2_frame_id = "map";        ///< frame_id of the poses: the field frame, in metres
  // --- live view (docs/DAEMON.md "Live view"; needs a build with cpp-httplib) ---
  int http_port = 0;  ///< TCP port of the live view's web page; 0: off
  /// IPv4 address it listens on (0.0.0.0: every interface)
  std::string http_address = "127.0.0.1";

  /// Checks ranges; throws ConfigError "<at>.<key>: <why> (got <value>)".
  void validate(const config::Origin& at) const;
  bool operator==(const DaemonConfig&) const = default;
};

/// config.validate(source).
void validate_daemon_config(const DaemonConfig& config, const std::string& source);

/// The key table (config_reader.hpp) that drives the JSON reader, the flags and --help.
[[nodiscard]] const std::vector<config::Key<DaemonConfig>>& daemon_config_keys();

/// Reads a JSON object of DaemonConfig keys over `base` (keys not present keep base's values) and
/// validates the result. Throws ConfigError naming the path (and the field) when the file is
/// missing, is not JSON, has an unknown or duplicate key, a value of the wrong type or out of
/// range.
[[nodiscard]] DaemonConfig load_daemon_config(const std::string& path,
                                              const DaemonConfig& base = {});

/// Sets one key from its text form (as a command-line flag gives it); throws ConfigError naming
/// `source` and the key when the key is unknown or the text is not a valid value.
void set_daemon_key(DaemonConfig& config, std::string_view key, std::string_view value,
                    const std::string& source);

}  // namespace omniloc::daemon
