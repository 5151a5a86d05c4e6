// The live view's server in a build without cpp-httplib (libcpp-httplib-dev): it refuses to start,
// saying why, so `--http-port` fails clearly instead of serving nothing.
#include <stdexcept>
#include <string>

#include "omniloc/live_view.hpp"

namespace omniloc::live {

struct LiveViewServer::Impl {};

LiveViewServer::LiveViewServer(LiveState&, const LiveViewOptions& options) {
  throw std::runtime_error(
      "live view (http_port " + std::to_string(options.port) +
      "): this build has no HTTP server; install libcpp-httplib-dev (scripts/deps.sh) and "
      "rebuild, or leave http_port at 0");
}

LiveViewServer::~LiveViewServer() = default;

int LiveViewServer::port() const {
  return 0;
}

bool LiveViewServer::available() {
  return false;
}

}  // namespace omniloc::live
