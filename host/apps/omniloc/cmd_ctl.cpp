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
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "omniloc/strict_number.hpp"

namespace omniloc::cli {

namespace {

void ctl_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: omniloc ctl [--port N] [--timeout-ms T] COMMAND\n"
               "  status                      the daemon's status and pose\n"
               "  set_pose X_CM Y_CM YAW_DEG  the robot stands there (field frame)\n"
               "  set_side blue|yellow        the colour of the goal the team defends\n"
               "  relocalize                  forget the fix: global search on the next frames\n"
               "  record start DIR | stop     start or stop a recording\n"
               "  --port        the daemon's control_port (default 5601), on 127.0.0.1\n"
               "  --timeout-ms  how long to wait for the reply (default 1000)\n"
               "Prints the reply (JSON); exit 0 for \"ok\": true, 1 for an error reply or no reply, 2 for bad usage.\n");
}

int usage_error(const std::string& why) {
  std::fprintf(stderr, "omniloc ctl: %s\n", why.c_str());
  ctl_usage(stderr);
  return 2;
}

}  // namespace

int cmd_ctl(std::span<const std::string_view> args) {
  int port = 5601;
  long timeout_ms = 1000;
  std::vector<std::string> words;
  try {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string_view a = args[i];
      if (a == "-h" || a == "--help") {
        ctl_usage(stdout);
        return 0;
      }
      if (a == "--port" || a == "--timeout-ms") {
        if (i + 1 >= args.size()) return usage_error(std::string(a) + " needs a value");
        const std::string_view v = args[++i];
        if (a == "--port")
          port = static_cast<int>(parse_int(v, "--port", 1, 65535));
        else
          timeout_ms = static_cast<long>(parse_int(v, "--timeout-ms", 1, 600'000));
        continue;
      }
      if (a.size() > 1 && a[0] == '-' && !(a[1] >= '0' && a[1] <= '9') && a[1] != '.')
        return usage_error("unknown option '" + std::string(a) + "'");
      words.emplace_back(a);
    }
    if (words.empty()) return usage_error("no command");
    nlohmann::json request = {{"id", static_cast<std::int64_t>(::getpid())}, {"cmd", words[0]}};
    const auto arity = [&](std::size_t n) {
      if (words.size() != n + 1)
        throw NumberError(words[0] + " takes " + std::to_string(n) + " argument(s), got " + std::to_string(words.size() - 1));
    };
    if (words[0] == "status" || words[0] == "relocalize") {
      arity(0);
    } else if (words[0] == "set_pose") {
      arity(3);
      request["x_cm"] = parse_double(words[1], "X_CM");
      request["y_cm"] = parse_double(words[2], "Y_CM");
      request["yaw_deg"] = parse_double(words[3], "YAW_DEG");
    } else if (words[0] == "set_side") {
      arity(1);
      request["side"] = words[1];
    } else if (words[0] == "record") {
      if (words.size() >= 2 && words[1] == "start") {
        arity(2);
        request["action"] = "start";
        request["dir"] = words[2];
      } else if (words.size() == 2 && words[1] == "stop") {
        request["action"] = "stop";
      } else {
        return usage_error("record takes 'start DIR' or 'stop'");
      }
    } else {
      return usage_error("unknown command '" + words[0] + "'");
    }

    const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
      std::fprintf(stderr, "omniloc ctl: socket: %s\n", std::strerror(errno));
      return 1;
    }
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const std::string text = request.dump();
    if (::sendto(fd, text.data(), text.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to) < 0) {
      std::fprintf(stderr, "omniloc ctl: send to 127.0.0.1:%d: %s\n", port, std::strerror(errno));
      ::close(fd);
      return 1;
    }
    pollfd p{fd, POLLIN, 0};
    char buf[65536];
    ssize_t n = -1;
    if (::poll(&p, 1, static_cast<int>(timeout_ms)) > 0) n = ::recv(fd, buf, sizeof buf, 0);
    ::close(fd);
    if (n < 0) {
      std::fprintf(stderr, "omniloc ctl: no reply from 127.0.0.1:%d within %ld ms (is omnilocd running, with control_port %d?)\n",
                   port, timeout_ms, port);
      return 1;
    }
    const std::string reply(buf, static_cast<std::size_t>(n));
    std::printf("%s\n", reply.c_str());
    const nlohmann::json j = nlohmann::json::parse(reply, nullptr, false);
    return j.is_object() && j.value("ok", false) ? 0 : 1;
  } catch (const NumberError& e) {
    return usage_error(e.what());
  }
}

}  // namespace omniloc::cli
