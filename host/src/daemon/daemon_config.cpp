// omnilocd configuration: one table of keys drives the JSON reader, the flag parser and --help, so
// the three cannot disagree about names or types.
#include "omniloc/daemon_config.hpp"

#include <arpa/inet.h>

#include <charconv>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>

namespace omniloc::daemon {
namespace {

enum class Kind { kText, kReal, kInt };

struct Key {
  std::string_view name;
  Kind kind;
  std::string_view help;
  std::function<void(DaemonConfig&, const std::string&, double)> set;  // text or number, by kind
  std::function<std::string(const DaemonConfig&)> show;
};

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

#define OMNILOC_TEXT_KEY(field, help) \
  Key{#field, Kind::kText, help, [](DaemonConfig& c, const std::string& s, double) { c.field = s; }, \
      [](const DaemonConfig& c) { return c.field.empty() ? std::string("\"\"") : c.field; }}
#define OMNILOC_REAL_KEY(field, help) \
  Key{#field, Kind::kReal, help, [](DaemonConfig& c, const std::string&, double v) { c.field = v; }, \
      [](const DaemonConfig& c) { return num(c.field); }}
#define OMNILOC_INT_KEY(field, type, help) \
  Key{#field, Kind::kInt, help, [](DaemonConfig& c, const std::string&, double v) { c.field = static_cast<type>(v); }, \
      [](const DaemonConfig& c) { return std::to_string(c.field); }}

const std::vector<Key>& keys() {
  static const std::vector<Key> table = {
      OMNILOC_TEXT_KEY(board, "usb | sim"),
      OMNILOC_TEXT_KEY(board_serial, "usb board serial, empty: first board"),
      OMNILOC_REAL_KEY(reconnect_period_ms, "ms between reopen attempts after an unplug"),
      OMNILOC_TEXT_KEY(camera, "sim | none | V4L2 index | device path | video file"),
      OMNILOC_REAL_KEY(camera_fps, "camera frames per second"),
      OMNILOC_REAL_KEY(camera_timeout_ms, "no frame for this long: odometry only"),
      OMNILOC_TEXT_KEY(field, "field geometry name or path"),
      OMNILOC_TEXT_KEY(camera_model, "camera model name or path"),
      OMNILOC_TEXT_KEY(robot, "robot config name or path"),
      OMNILOC_TEXT_KEY(localizer, "localizer config name or path"),
      OMNILOC_TEXT_KEY(database, "feature database file; empty: build at start-up"),
      OMNILOC_REAL_KEY(grid_step_cm, "grid step of a database built at start-up"),
      OMNILOC_TEXT_KEY(udp_address, "IPv4 address the poses are sent to"),
      OMNILOC_INT_KEY(udp_port, int, "UDP port the poses are sent to"),
      OMNILOC_REAL_KEY(publish_hz, "pose rate (the board window rate, 100)"),
      OMNILOC_TEXT_KEY(record_dir, "record the session here; empty: no recording"),
      OMNILOC_REAL_KEY(status_period_s, "seconds between status lines; 0: none"),
      OMNILOC_REAL_KEY(duration_s, "stop after this many seconds; 0: run until SIGINT/SIGTERM"),
      OMNILOC_TEXT_KEY(sim_trajectory, "simulated robot's trajectory"),
      OMNILOC_INT_KEY(sim_seed, std::uint64_t, "simulation seed"),
  };
  return table;
}

const Key* find_key(std::string_view name) {
  for (const auto& k : keys())
    if (k.name == name) return &k;
  return nullptr;
}

[[noreturn]] void fail(const std::string& source, std::string_view field, const std::string& why) {
  throw ConfigError(source + ": field '" + std::string(field) + "': " + why);
}

void set_number(DaemonConfig& c, const Key& k, double v, const std::string& source, const std::string& shown) {
  if (!std::isfinite(v)) fail(source, k.name, "must be a finite number (got " + shown + ")");
  if (k.kind == Kind::kInt && (v != std::floor(v) || v < 0 || v > 9.0e15))
    fail(source, k.name, "must be a non-negative integer (got " + shown + ")");
  k.set(c, {}, v);
}

void require(bool ok, const std::string& source, std::string_view field, const std::string& why,
             const std::string& got) {
  if (!ok) fail(source, field, why + " (got " + got + ")");
}

}  // namespace

void validate_daemon_config(const DaemonConfig& c, const std::string& source) {
  require(c.board == "usb" || c.board == "sim", source, "board", "must be \"usb\" or \"sim\"", c.board);
  require(c.reconnect_period_ms >= 1 && c.reconnect_period_ms <= 60'000, source, "reconnect_period_ms",
          "must be in [1, 60000]", num(c.reconnect_period_ms));
  require(!c.camera.empty(), source, "camera", "must not be empty", "\"\"");
  require(c.camera_fps > 0 && c.camera_fps <= 240, source, "camera_fps", "must be in (0, 240]", num(c.camera_fps));
  require(c.camera_timeout_ms >= 10 && c.camera_timeout_ms <= 60'000, source, "camera_timeout_ms",
          "must be in [10, 60000]", num(c.camera_timeout_ms));
  require(!c.field.empty(), source, "field", "must not be empty", "\"\"");
  require(!c.camera_model.empty(), source, "camera_model", "must not be empty", "\"\"");
  require(!c.robot.empty(), source, "robot", "must not be empty", "\"\"");
  require(!c.localizer.empty(), source, "localizer", "must not be empty", "\"\"");
  require(c.grid_step_cm >= 2 && c.grid_step_cm <= 50, source, "grid_step_cm", "must be in [2, 50]",
          num(c.grid_step_cm));
  in_addr addr{};
  require(inet_pton(AF_INET, c.udp_address.c_str(), &addr) == 1, source, "udp_address",
          "must be a dotted IPv4 address", "\"" + c.udp_address + "\"");
  require(c.udp_port >= 1 && c.udp_port <= 65535, source, "udp_port", "must be in [1, 65535]",
          std::to_string(c.udp_port));
  // One datagram per board window: the rate is the board's, so the only value accepted is 100.
  require(c.publish_hz == 100.0, source, "publish_hz", "must be 100 (one pose per 10 ms board window)",
          num(c.publish_hz));
  require(c.status_period_s >= 0 && c.status_period_s <= 3600, source, "status_period_s", "must be in [0, 3600]",
          num(c.status_period_s));
  require(c.duration_s >= 0, source, "duration_s", "must be >= 0", num(c.duration_s));
  require(!c.sim_trajectory.empty(), source, "sim_trajectory", "must not be empty", "\"\"");
}

DaemonConfig load_daemon_config(const std::string& path, const DaemonConfig& base) {
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON))
      throw ConfigError(path + ": cannot open the daemon config file");
  } catch (const cv::Exception& e) {
    throw ConfigError(path + ": not a valid JSON file: " + e.msg);
  }
  const cv::FileNode root = fs.root();
  if (!root.isMap()) throw ConfigError(path + ": the top level must be a JSON object");
  DaemonConfig c = base;
  for (const std::string& name : root.keys()) {
    const Key* k = find_key(name);
    if (!k) fail(path, name, "unknown key (see docs/DAEMON.md)");
    const cv::FileNode n = root[name];
    if (k->kind == Kind::kText) {
      if (!n.isString()) fail(path, name, "must be a string");
      k->set(c, n.string(), 0.0);
    } else {
      if (!n.isInt() && !n.isReal()) fail(path, name, "must be a number");
      const double v = n.real();
      set_number(c, *k, v, path, num(v));
    }
  }
  validate_daemon_config(c, path);
  return c;
}

void set_daemon_key(DaemonConfig& c, std::string_view key, std::string_view value, const std::string& source) {
  const Key* k = find_key(key);
  if (!k) fail(source, key, "unknown key (see --help)");
  const std::string text(value);
  if (k->kind == Kind::kText) {
    k->set(c, text, 0.0);
    return;
  }
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty())
    fail(source, key, "must be a number (got \"" + text + "\")");
  set_number(c, *k, v, source, text);
}

DaemonArgs parse_daemon_args(std::span<const std::string_view> args) {
  DaemonArgs out;
  // --config first, so that flags override the file whatever their order.
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--config") {
      if (i + 1 >= args.size()) throw ConfigError("command line: --config needs a file");
      out.config_path = std::string(args[i + 1]);
    }
  }
  if (!out.config_path.empty()) out.config = load_daemon_config(out.config_path);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (a == "-h" || a == "--help") {
      out.help = true;
      continue;
    }
    if (a == "--config") {
      ++i;
      continue;
    }
    if (a.size() < 3 || a.substr(0, 2) != "--") throw ConfigError("command line: unexpected argument '" + std::string(a) + "'");
    std::string key(a.substr(2));
    for (char& ch : key)
      if (ch == '-') ch = '_';
    if (i + 1 >= args.size()) throw ConfigError("command line: " + std::string(a) + " needs a value");
    set_daemon_key(out.config, key, args[++i], "command line");
  }
  validate_daemon_config(out.config, out.config_path.empty() ? "command line" : out.config_path + " + command line");
  return out;
}

std::string daemon_usage() {
  std::ostringstream os;
  os << "usage: omnilocd [--config FILE] [--KEY VALUE ...] [--help]\n\n"
        "The robot's localization daemon: board (USB or simulated) + camera -> localizer -> UDP poses.\n"
        "Flags override the config file (JSON, docs/DAEMON.md). Keys (default):\n";
  const DaemonConfig d;
  for (const auto& k : keys()) {
    std::string flag(k.name);
    for (char& ch : flag)
      if (ch == '_') ch = '-';
    os << "  --" << flag << std::string(flag.size() < 22 ? 22 - flag.size() : 1, ' ') << k.help << " (" << k.show(d)
       << ")\n";
  }
  os << "\nSIGINT / SIGTERM stop it cleanly (recording closed, board streaming switched off).\n";
  return os.str();
}

}  // namespace omniloc::daemon
