// `omniloc ctl COMMAND ...`: the client of omnilocd's control channel (control.hpp,
// docs/DAEMON.md "Control channel"): one request datagram, one reply printed on stdout.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "omniloc/detail/strict_number.hpp"

namespace omniloc::cli {

namespace {

constexpr const char* kCommands =
    "COMMAND is one of:\n"
    "  status                      the daemon's status and pose\n"
    "  set_pose X_CM Y_CM YAW_DEG  the robot stands there (field frame)\n"
    "  set_side blue|yellow        the colour of the goal the team defends\n"
    "  relocalize                  forget the fix: global search on the next frames\n"
    "  record start DIR | stop     start or stop a recording\n"
    "Prints the reply (JSON); exit 0 for \"ok\": true, 1 for an error reply or no reply, 2 for bad "
    "usage.";

struct CtlArgs {
  int port = 5601;
  int timeout_ms = 1000;
  std::vector<std::string> words;
};

/// A request that cannot be sent: bad usage (exit 2).
class UsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The request datagram the words ask for; throws UsageError (or NumberError for a bad number).
nlohmann::json request_of(const std::vector<std::string>& words) {
  nlohmann::json request = {{"id", static_cast<std::int64_t>(::getpid())}, {"cmd", words[0]}};
  const auto arity = [&](std::size_t n) {
    if (words.size() != n + 1)
      throw UsageError(words[0] + " takes " + std::to_string(n) + " argument(s), got " +
                       std::to_string(words.size() - 1));
  };
  if (words[0] == "status" || words[0] == "relocalize") {
    arity(0);
  } else if (words[0] == "set_pose") {
    arity(3);
    // Any finite number goes to the daemon, which checks it against the field (its reply says why
    // not).
    request["x_cm"] = parse_double(words[1], "set_pose X_CM", -1e9, 1e9);
    request["y_cm"] = parse_double(words[2], "set_pose Y_CM", -1e9, 1e9);
    request["yaw_deg"] = parse_double(words[3], "set_pose YAW_DEG", -1e9, 1e9);
  } else if (words[0] == "set_side") {
    arity(1);
    request["side"] = words[1];
  } else if (words[0] == "record" && words.size() >= 2 && words[1] == "start") {
    arity(2);
    request["action"] = "start";
    request["dir"] = words[2];
  } else if (words[0] == "record" && words.size() == 2 && words[1] == "stop") {
    request["action"] = "stop";
  } else if (words[0] == "record") {
    throw UsageError("record takes 'start DIR' or 'stop'");
  } else {
    throw UsageError("unknown command '" + words[0] + "'");
  }
  return request;
}

/// Sends the request to 127.0.0.1:port, prints the reply: 0 for "ok": true, else 1.
int send_request(const CtlArgs& a, const nlohmann::json& request) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    std::fprintf(stderr, "omniloc ctl: socket: %s\n", std::strerror(errno));
    return 1;
  }
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(a.port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const std::string text = request.dump();
  if (::sendto(fd, text.data(), text.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to) < 0) {
    std::fprintf(stderr, "omniloc ctl: send to 127.0.0.1:%d: %s\n", a.port, std::strerror(errno));
    ::close(fd);
    return 1;
  }
  pollfd p{fd, POLLIN, 0};
  char buf[65536];
  ssize_t n = -1;
  if (::poll(&p, 1, a.timeout_ms) > 0) n = ::recv(fd, buf, sizeof buf, 0);
  ::close(fd);
  if (n < 0) {
    std::fprintf(stderr,
                 "omniloc ctl: no reply from 127.0.0.1:%d within %d ms (is omnilocd running, with "
                 "control_port %d?)\n",
                 a.port, a.timeout_ms, a.port);
    return 1;
  }
  const std::string reply(buf, static_cast<std::size_t>(n));
  std::printf("%s\n", reply.c_str());
  const nlohmann::json j = nlohmann::json::parse(reply, nullptr, false);
  return j.is_object() && j.value("ok", false) ? 0 : 1;
}

int run_ctl(const CtlArgs& a) {
  nlohmann::json request;
  try {
    request = request_of(a.words);
  } catch (const std::invalid_argument& e) {  // UsageError, NumberError
    std::fprintf(stderr, "omniloc ctl: error: %s\n%s\n", e.what(), kCommands);
    return 2;
  }
  return send_request(a, request);
}

}  // namespace

Subcommand add_ctl(CLI::App& program) {
  CLI::App* app = program.add_subcommand(
      "ctl",
      "talk to a running omnilocd: status, set_pose, set_side, relocalize, record start|stop");
  auto a = std::make_shared<CtlArgs>();
  app->add_option("COMMAND", a->words, "the request and its arguments (below)")->required();
  add_number_option(*app, "--port", a->port, "the daemon's control_port, on 127.0.0.1", 1, 65535);
  add_number_option(*app, "--timeout-ms", a->timeout_ms, "how long to wait for the reply", 1,
                    600'000);
  app->footer(kCommands);
  return {app, [a] { return run_ctl(*a); }};
}

}  // namespace omniloc::cli
