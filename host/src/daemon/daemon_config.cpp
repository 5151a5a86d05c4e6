// omnilocd configuration: one table of keys drives the JSON reader, the flags and --help (CLI11 in
// host/apps/common/daemon_cli.hpp), so the three cannot disagree about names or types.
#include "omniloc/daemon_config.hpp"

#include <arpa/inet.h>

#include <cmath>
#include <sstream>

#include "omniloc/detail/config_reader.hpp"
#include "omniloc/ros2_bridge.hpp"

namespace omniloc::daemon {

using config::Need;

const config::KeyTable<DaemonConfig>& daemon_config_keys() {
  using config::key;
  using D = DaemonConfig;
  constexpr Need opt = Need::kOptional;
  static const config::KeyTable<DaemonConfig> table = {
      key("board_serial", &D::board_serial, opt, "USB board serial, empty: first board"),
      key("reconnect_period_ms", &D::reconnect_period_ms, opt,
          "ms between reopen attempts after an unplug"),
      key("camera", &D::camera, opt, "none | V4L2 index | device path | video file"),
      key("camera_fps", &D::camera_fps, opt, "camera frames per second"),
      key("camera_timeout_ms", &D::camera_timeout_ms, opt, "no frame for this long: odometry only"),
      key("camera_latency_ms", &D::camera_latency_ms, opt,
          "exposure to hand-over of a frame without a driver timestamp"),
      key("field", &D::field, opt, "field geometry name or path"),
      key("camera_model", &D::camera_model, opt, "camera model name or path"),
      key("robot", &D::robot, opt, "robot config name or path"),
      key("localizer", &D::localizer, opt, "localizer config name or path"),
      key("database", &D::database, opt, "feature database file; empty: build at start-up"),
      key("grid_step_cm", &D::grid_step_cm, opt, "grid step of a database built at start-up"),
      config::choice<D, std::string>(
          "side", &D::side, {{"unknown", "unknown"}, {"blue", "blue"}, {"yellow", "yellow"}}, opt,
          "the colour of the goal the team defends: blue | yellow | unknown"),
      key("udp_address", &D::udp_address, opt, "IPv4 address the poses are sent to"),
      config::ranged("udp_port", &D::udp_port, 1, 65535, opt, "UDP port the poses are sent to"),
      key("publish_hz", &D::publish_hz, opt, "pose rate (the board window rate, 100)"),
      key("control_port", &D::control_port, opt,
          "UDP port of the control channel on 127.0.0.1; 0: off"),
      key("record_dir", &D::record_dir, opt,
          "record the session here (a new or empty directory); empty: no recording"),
      key("record_overwrite", &D::record_overwrite, opt,
          "replace an old recording in record_dir (its frames too)"),
      config::choice<D, std::string>(
          "record_format", &D::record_format, {{"jpeg", "jpeg"}, {"png", "png"}}, opt,
          "recorded frames: jpeg (~2 MB/s at 30 Hz 640 x 480) or png (lossless, ~12 MB/s)"),
      key("status_period_s", &D::status_period_s, opt, "seconds between status lines; 0: none"),
      config::choice<D, std::string>(
          "log_level", &D::log_level,
          {{"error", "error"}, {"warning", "warning"}, {"info", "info"}, {"debug", "debug"}}, opt,
          "least severe messages logged: error, warning, info (status lines), debug"),
      key("duration_s", &D::duration_s, opt,
          "stop after this many seconds; 0: run until SIGINT/SIGTERM"),
      key("ros2_domain_id", &D::ros2_domain_id, opt,
          "ROS 2 topics in this DDS domain (ROS_DOMAIN_ID); -1: off"),
      key("ros2_namespace", &D::ros2_namespace, opt,
          "ROS 2 namespace of the topics: <ns>/pose, <ns>/odom"),
      key("ros2_frame_id", &D::ros2_frame_id, opt,
          "frame_id of the published poses (the field frame)"),
      key("http_port", &D::http_port, opt,
          "live view: a web page on this TCP port (http://ADDRESS:PORT/); 0: off"),
      key("http_address", &D::http_address, opt,
          "IPv4 address the live view listens on; 0.0.0.0: every interface"),
  };
  return table;
}

void DaemonConfig::validate(const config::Origin& at) const {
  using config::require;
  using config::show;
  require(reconnect_period_ms >= 1 && reconnect_period_ms <= 60'000, at / "reconnect_period_ms",
          "must be in [1, 60000]", reconnect_period_ms);
  require(!camera.empty(), at / "camera", "must not be empty", show(camera));
  require(camera_fps > 0 && camera_fps <= 240, at / "camera_fps", "must be in (0, 240]",
          camera_fps);
  require(camera_timeout_ms >= 10 && camera_timeout_ms <= 60'000, at / "camera_timeout_ms",
          "must be in [10, 60000]", camera_timeout_ms);
  require(camera_latency_ms >= 0 && camera_latency_ms <= 1000, at / "camera_latency_ms",
          "must be in [0, 1000]", camera_latency_ms);
  require(!field.empty(), at / "field", "must not be empty", show(field));
  require(!camera_model.empty(), at / "camera_model", "must not be empty", show(camera_model));
  require(!robot.empty(), at / "robot", "must not be empty", show(robot));
  require(!localizer.empty(), at / "localizer", "must not be empty", show(localizer));
  require(grid_step_cm >= 2 && grid_step_cm <= 50, at / "grid_step_cm", "must be in [2, 50]",
          grid_step_cm);
  in_addr addr{};
  require(inet_pton(AF_INET, udp_address.c_str(), &addr) == 1, at / "udp_address",
          "must be a dotted IPv4 address", show(udp_address));
  require(udp_port >= 1 && udp_port <= 65535, at / "udp_port", "must be in [1, 65535]", udp_port);
  require(control_port >= 0 && control_port <= 65535, at / "control_port",
          "must be 0 (off) or in [1, 65535]", control_port);
  // One datagram per board window: the rate is the board's, so the only value accepted is 100.
  require(publish_hz == 100.0, at / "publish_hz", "must be 100 (one pose per 10 ms board window)",
          publish_hz);
  require(status_period_s >= 0 && status_period_s <= 3600, at / "status_period_s",
          "must be in [0, 3600]", status_period_s);
  require(std::isfinite(duration_s) && duration_s >= 0, at / "duration_s", "must be >= 0",
          duration_s);
  require(ros2_domain_id >= -1 && ros2_domain_id <= 232, at / "ros2_domain_id",
          "must be -1 (off) or in [0, 232]", ros2_domain_id);
  try {
    (void)ros2::dds_topic_name(ros2_namespace + "/pose");
  } catch (const std::invalid_argument&) {
    require(false, at / "ros2_namespace", "must be an absolute ROS 2 name such as /omniloc",
            show(ros2_namespace));
  }
  require(!ros2_frame_id.empty(), at / "ros2_frame_id", "must not be empty", show(ros2_frame_id));
  require(http_port >= 0 && http_port <= 65535, at / "http_port",
          "must be 0 (off) or in [1, 65535]", http_port);
  require(inet_pton(AF_INET, http_address.c_str(), &addr) == 1, at / "http_address",
          "must be a dotted IPv4 address", show(http_address));
}

void validate_daemon_config(const DaemonConfig& c, const std::string& source) {
  c.validate(source);
}

DaemonConfig load_daemon_config(const std::string& path, const DaemonConfig& base) {
  const config::Document doc = config::parse_json_file(path);
  DaemonConfig c = base;
  config::read_keys(doc.root(), daemon_config_keys(), c);
  c.validate(path);
  return c;
}

void set_daemon_key(DaemonConfig& c, std::string_view key, std::string_view value,
                    const std::string& source) {
  const config::Origin at = config::Origin(source) / key;
  const config::Key<DaemonConfig>* k = config::find_key(daemon_config_keys(), key);
  if (!k) at.fail("unknown key (see --help)");
  // A flag's text is the value of a text key, and the JSON of any other (a number: 5600, 0.5).
  config::Json json;
  if (k->kind == config::Kind::kText) {
    json = std::string(value);
  } else {
    try {
      json = config::Json::parse(value);
    } catch (const config::Json::exception&) {
      at.fail(k->kind == config::Kind::kNumber ? "must be a number" : "must be a JSON value",
              config::show(value));
    }
  }
  k->read(config::Node(json, at), c);
}

}  // namespace omniloc::daemon
