// omnilocd's control channel (docs/DAEMON.md, "Control channel"): JSON requests in UDP datagrams
// to 127.0.0.1:<control_port>, one reply datagram back to the sender. The parser and the reply
// formatter are plain functions (no sockets) so that they can be tested and fuzzed alone.
//
//   {"id": 7, "cmd": "status"}
//   {"id": 8, "cmd": "set_pose", "x_cm": 375, "y_cm": 275, "yaw_deg": 0}
//   {"id": 9, "cmd": "set_side", "side": "blue"}
//   {"id": 10, "cmd": "relocalize"}
//   {"id": 11, "cmd": "record", "action": "start", "dir": "/data/rec1"}
//   {"id": 12, "cmd": "record", "action": "stop"}
// Replies: {"id": 7, "ok": true, ...} or {"id": 7, "ok": false, "error": "<what was wrong>"}; "id"
// is echoed (null when the request had none or could not be read).
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>

#include <nlohmann/json.hpp>

namespace omniloc::control {

/// Larger datagrams are refused unread (a request is a few dozen bytes).
inline constexpr std::size_t kMaxRequestBytes = 4096;

struct Status {};
struct SetPose {
  double x_cm = 0.0;
  double y_cm = 0.0;
  double yaw_deg = 0.0;
};
struct SetSide {
  std::string side;  ///< "blue" or "yellow": the colour of the goal the team defends
};
struct Relocalize {};
struct RecordStart {
  std::string dir;
};
struct RecordStop {};

using Command = std::variant<Status, SetPose, SetSide, Relocalize, RecordStart, RecordStop>;

struct Request {
  std::optional<std::int64_t> id;
  Command command;
};

/// A request that cannot be carried out, or could not be read; id() is the request's id if it had
/// a readable one. what() is the text of the error reply.
class ControlError : public std::runtime_error {
 public:
  ControlError(std::optional<std::int64_t> id, const std::string& what)
      : std::runtime_error(what), id_(id) {}
  [[nodiscard]] std::optional<std::int64_t> id() const { return id_; }

 private:
  std::optional<std::int64_t> id_;
};

/// Parses one datagram; throws ControlError naming what is wrong: too large, not JSON, not an
/// object, a missing or non-integer id, an unknown cmd, a missing, unknown, wrongly typed or
/// out-of-range field (numbers finite, |x|, |y| <= 10000 cm, |yaw| <= 360 deg, dir non-empty).
[[nodiscard]] Request parse_request(std::string_view datagram);

/// The name of a command as it is written in a request ("set_pose").
[[nodiscard]] std::string_view command_name(const Command& command);

/// {"id": id, "ok": true, <fields>} on one line (fields must be an object; may be empty).
[[nodiscard]] std::string ok_reply(std::optional<std::int64_t> id,
                                   const nlohmann::json& fields = nlohmann::json::object());
/// {"id": id, "ok": false, "error": error} on one line.
[[nodiscard]] std::string error_reply(std::optional<std::int64_t> id, std::string_view error);

/// A non-blocking UDP socket bound to an IPv4 address and port, for the daemon's side.
class ControlSocket {
 public:
  /// Throws std::runtime_error naming the address and port when it cannot be bound.
  ControlSocket(const std::string& ipv4_address, int port);
  ~ControlSocket();
  ControlSocket(const ControlSocket&) = delete;
  ControlSocket& operator=(const ControlSocket&) = delete;

  struct Datagram {
    std::string text;
    std::size_t size = 0;         ///< the datagram's real size
    bool truncated = false;       ///< longer than kMaxRequestBytes (the text is cut there)
    unsigned char from[16] = {};  ///< sockaddr_in of the sender, for the reply
  };
  /// The next waiting datagram, or nullopt at once when there is none.
  [[nodiscard]] std::optional<Datagram> receive();
  /// Sends `reply` to the datagram's sender; a failure is counted, never thrown.
  void reply(const Datagram& to, std::string_view reply);

 private:
  int fd_ = -1;
};

}  // namespace omniloc::control
