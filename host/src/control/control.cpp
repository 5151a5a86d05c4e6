#include "omniloc/control.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "omniloc/detail/config_reader.hpp"

namespace omniloc::control {

namespace {

using nlohmann::json;

// Every command and the fields it takes besides "id" and "cmd" (anything else is refused by name):
// the one list the parser checks names, fields and its "unknown cmd" message against.
const std::map<std::string, std::set<std::string>, std::less<>>& commands() {
  static const std::map<std::string, std::set<std::string>, std::less<>> table = {
      {"status", {}},
      {"set_pose", {"x_cm", "y_cm", "yaw_deg"}},
      {"set_side", {"side"}},
      {"relocalize", {}},
      {"record", {"action", "dir"}},
  };
  return table;
}

std::string command_list() {
  std::string out;
  for (const auto& [name, fields] : commands()) out += (out.empty() ? "" : ", ") + name;
  return out;
}

struct Reader {
  const json& j;
  std::optional<std::int64_t> id;
  std::string cmd;

  [[noreturn]] void fail(const std::string& why) const { throw ControlError(id, cmd + ": " + why); }

  double number(const char* key, double limit) const {
    if (!j.contains(key)) fail(std::string("missing field '") + key + "'");
    const json& v = j[key];
    if (!v.is_number())
      fail(std::string("field '") + key + "' must be a number (got " + v.dump() + ")");
    const double d = v.get<double>();
    if (!std::isfinite(d) || std::fabs(d) > limit)
      fail(std::string("field '") + key + "' must be within +-" + json(limit).dump() + " (got " +
           v.dump() + ")");
    return d;
  }

  std::string text(const char* key) const {
    if (!j.contains(key)) fail(std::string("missing field '") + key + "'");
    const json& v = j[key];
    if (!v.is_string())
      fail(std::string("field '") + key + "' must be a string (got " + v.dump() + ")");
    return v.get<std::string>();
  }
};

std::optional<std::int64_t> read_id(const json& j) {
  if (!j.contains("id") || j["id"].is_null()) return std::nullopt;
  const json& v = j["id"];
  if (!v.is_number_integer())
    throw ControlError(std::nullopt, "field 'id' must be an integer (got " + v.dump() + ")");
  if (v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(INT64_MAX))
    throw ControlError(std::nullopt, "field 'id' is out of range (got " + v.dump() + ")");
  return v.get<std::int64_t>();
}

// A key given twice, refused as every file reader refuses it (config::parse_json_text: "request:
// x_cm: duplicate key: an object may give a key only once (got "x_cm" a second time)"); nlohmann
// alone keeps the last value. The reply carries the id unless "id" is the key given twice.
void refuse_duplicate_keys(std::string_view datagram, const json& parsed) {
  try {
    (void)config::parse_json_text(datagram, "request");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    std::optional<std::int64_t> id;
    if (what.rfind("request:id:", 0) != 0) {
      try {
        id = read_id(parsed);
      } catch (const ControlError&) {
      }
    }
    throw ControlError(id, what);
  }
}

}  // namespace

Request parse_request(std::string_view datagram) {
  if (datagram.size() > kMaxRequestBytes)
    throw ControlError(std::nullopt, "request of " + std::to_string(datagram.size()) +
                                         " bytes is larger than " +
                                         std::to_string(kMaxRequestBytes));
  json j;
  try {
    j = json::parse(datagram);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for 1e999
    throw ControlError(std::nullopt, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object())
    throw ControlError(std::nullopt,
                       "a request must be a JSON object (got " + std::string(j.type_name()) + ")");
  refuse_duplicate_keys(datagram, j);
  Reader r{j, read_id(j), ""};
  if (!j.contains("cmd")) throw ControlError(r.id, "missing field 'cmd'");
  if (!j["cmd"].is_string())
    throw ControlError(r.id, "field 'cmd' must be a string (got " + j["cmd"].dump() + ")");
  r.cmd = j["cmd"].get<std::string>();
  const auto command = commands().find(r.cmd);
  if (command == commands().end())
    throw ControlError(r.id, "unknown cmd '" + r.cmd + "' (" + command_list() + ")");
  for (const auto& [key, value] : j.items())
    if (key != "id" && key != "cmd" && !command->second.contains(key))
      r.fail("unknown field '" + key + "'");

  Request q{r.id, Status{}};
  if (r.cmd == "set_pose") {
    q.command =
        SetPose{r.number("x_cm", 10000.0), r.number("y_cm", 10000.0), r.number("yaw_deg", 360.0)};
  } else if (r.cmd == "set_side") {
    const std::string side = r.text("side");
    if (side != "blue" && side != "yellow")
      r.fail("field 'side' must be \"blue\" or \"yellow\" (got " + j["side"].dump() + ")");
    q.command = SetSide{side};
  } else if (r.cmd == "relocalize") {
    q.command = Relocalize{};
  } else if (r.cmd == "record") {
    const std::string action = r.text("action");
    if (action == "start") {
      const std::string dir = r.text("dir");
      if (dir.empty()) r.fail("field 'dir' must not be empty");
      q.command = RecordStart{dir};
    } else if (action == "stop") {
      if (j.contains("dir")) r.fail("field 'dir' is for action \"start\" only");
      q.command = RecordStop{};
    } else {
      r.fail("field 'action' must be \"start\" or \"stop\" (got " + j["action"].dump() + ")");
    }
  }
  return q;
}

std::string_view command_name(const Command& command) {
  struct Name {
    std::string_view operator()(const Status&) const { return "status"; }
    std::string_view operator()(const SetPose&) const { return "set_pose"; }
    std::string_view operator()(const SetSide&) const { return "set_side"; }
    std::string_view operator()(const Relocalize&) const { return "relocalize"; }
    std::string_view operator()(const RecordStart&) const { return "record"; }
    std::string_view operator()(const RecordStop&) const { return "record"; }
  };
  return std::visit(Name{}, command);
}

std::string ok_reply(std::optional<std::int64_t> id, const nlohmann::json& fields) {
  json out = json::object();
  out["id"] = id ? json(*id) : json(nullptr);
  out["ok"] = true;
  for (const auto& [k, v] : fields.items()) out[k] = v;
  // dump() with replacement: a file name in an error or field is not always valid UTF-8.
  return out.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string error_reply(std::optional<std::int64_t> id, std::string_view error) {
  json out = json::object();
  out["id"] = id ? json(*id) : json(nullptr);
  out["ok"] = false;
  out["error"] = std::string(error);
  return out.dump(-1, ' ', false, json::error_handler_t::replace);
}

ControlSocket::ControlSocket(const std::string& ipv4_address, int port) {
  const std::string where = ipv4_address + ":" + std::to_string(port);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0)
    throw std::runtime_error("control channel " + where + ": socket: " + std::strerror(errno));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, ipv4_address.c_str(), &a.sin_addr) != 1) {
    ::close(fd_);
    throw std::runtime_error("control channel " + where + ": not a dotted IPv4 address");
  }
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const int e = errno;
    ::close(fd_);
    throw std::runtime_error(
        "control channel " + where + ": bind: " + std::strerror(e) +
        (e == EADDRINUSE ? " (another omnilocd running? set control_port)" : ""));
  }
}

ControlSocket::~ControlSocket() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<ControlSocket::Datagram> ControlSocket::receive() {
  Datagram d;
  char buf[kMaxRequestBytes + 1];
  sockaddr_in from{};
  socklen_t len = sizeof from;
  const ssize_t n =
      ::recvfrom(fd_, buf, sizeof buf, MSG_TRUNC, reinterpret_cast<sockaddr*>(&from), &len);
  if (n < 0)
    return std::nullopt;  // EAGAIN: nothing waiting (any other error: nothing to read either)
  d.size = static_cast<std::size_t>(n);
  d.truncated = d.size > kMaxRequestBytes;
  d.text.assign(buf, std::min(d.size, kMaxRequestBytes));
  static_assert(sizeof(sockaddr_in) <= sizeof d.from);
  std::memcpy(d.from, &from, sizeof from);
  return d;
}

void ControlSocket::reply(const Datagram& to, std::string_view reply) {
  sockaddr_in a{};
  std::memcpy(&a, to.from, sizeof a);
  // A reply that cannot be sent (the client gone, a full socket buffer) is lost like any UDP
  // datagram: the client asks again after its timeout, and the daemon's loop must not wait.
  (void)::sendto(fd_, reply.data(), reply.size(), MSG_DONTWAIT,
                 reinterpret_cast<const sockaddr*>(&a), sizeof a);
}

}  // namespace omniloc::control
