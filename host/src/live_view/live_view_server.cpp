// The live view's HTTP server (live_view.hpp) on cpp-httplib: a listening thread and a pool of
// four workers; each connection serves one request (no keep-alive), so a browser's parallel
// connections never wait for an idle one to time out.
// Our headers (Eigen) first: httplib.h brings <resolv.h>, whose `_res` macro breaks Eigen's
// parameter names when Eigen comes after it.
#include "omniloc/live_view.hpp"

#include <httplib.h>

#include <sys/socket.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

namespace omniloc::live {

struct LiveViewServer::Impl {
  httplib::Server server;
  std::thread thread;
  std::atomic<bool> finished{false};
  int port = 0;
};

namespace {

void no_cache(httplib::Response& res) {
  res.set_header("Cache-Control", "no-store");
}

// The server's limits: four workers, one request per connection, short timeouts, small requests
// (the page only GETs), and the port never shared with another daemon.
void configure(httplib::Server& s) {
  s.new_task_queue = [] { return new httplib::ThreadPool(4); };
  s.set_keep_alive_max_count(1);
  // SO_REUSEADDR only: httplib's default adds SO_REUSEPORT, with which a second daemon on the same
  // port would share it silently instead of being refused.
  s.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  s.set_read_timeout(2, 0);
  s.set_write_timeout(2, 0);
  s.set_payload_max_length(4096);  // the page only GETs
}

// The page and what it polls: the JSON documents (503 before the first pose) and the camera's
// frame (503 before the first frame), none of them cached.
void add_routes(httplib::Server& s, LiveState& state) {
  s.Get("/", [](const httplib::Request&, httplib::Response& res) {
    const std::string_view page = LiveState::page_html();
    res.set_content(page.data(), page.size(), "text/html; charset=utf-8");
  });
  auto json = [&state](std::string (LiveState::*get)() const) {
    return [&state, get](const httplib::Request&, httplib::Response& res) {
      no_cache(res);
      std::string body = (state.*get)();
      if (body.empty()) {
        res.status = 503;
        res.set_content(R"({"error":"no pose yet"})", "application/json");
        return;
      }
      res.set_content(std::move(body), "application/json");
    };
  };
  s.Get("/pose.json", json(&LiveState::pose_json));
  s.Get("/status.json", json(&LiveState::status_json));
  s.Get("/state.json", json(&LiveState::state_json));
  s.Get("/field.json", json(&LiveState::field_json));
  auto image = [&state](std::shared_ptr<const std::vector<unsigned char>> (LiveState::*get)(),
                        const char* type) {
    return [&state, get, type](const httplib::Request&, httplib::Response& res) {
      no_cache(res);
      const auto bytes = (state.*get)();
      if (!bytes) {
        res.status = 503;
        res.set_content("no camera frame yet", "text/plain");
        return;
      }
      res.set_content(reinterpret_cast<const char*>(bytes->data()), bytes->size(), type);
    };
  };
  s.Get("/frame.jpg", image(&LiveState::frame_jpeg, "image/jpeg"));
  s.Get("/frame.png", image(&LiveState::frame_png, "image/png"));
}

}  // namespace

LiveViewServer::LiveViewServer(LiveState& state, const LiveViewOptions& options)
    : impl_(std::make_unique<Impl>()) {
  httplib::Server& s = impl_->server;
  configure(s);
  add_routes(s, state);
  const std::string where =
      "live view: http://" + options.address + ":" + std::to_string(options.port) + "/";
  if (options.port == 0) {
    impl_->port = s.bind_to_any_port(options.address);
    if (impl_->port <= 0) throw std::runtime_error(where + ": cannot listen on " + options.address);
  } else {
    if (!s.bind_to_port(options.address, options.port))
      throw std::runtime_error(where +
                               ": cannot listen (port in use, or not an address of this host)");
    impl_->port = options.port;
  }
  impl_->thread = std::thread([this] {
    impl_->server.listen_after_bind();
    impl_->finished = true;
  });
  // Until it accepts: stop() before that would be lost and the destructor would wait forever.
  for (int i = 0; i < 5000 && !impl_->server.is_running() && !impl_->finished; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

LiveViewServer::~LiveViewServer() {
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

int LiveViewServer::port() const {
  return impl_->port;
}

bool LiveViewServer::available() {
  return true;
}

}  // namespace omniloc::live
