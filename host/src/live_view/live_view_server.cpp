// The live view's HTTP server (live_view.hpp) on cpp-httplib: a listening thread, a waiting room
// and a pool of four workers. A connection that has sent nothing yet waits in the waiting room (one
// thread polls them all), never in a worker: idle connections cost a socket each, bounded in
// number and time, and cannot keep the page from its workers. Each connection serves one request
// (no keep-alive), so a browser's parallel connections never wait for an idle one to time out.
// Our headers (Eigen) first: httplib.h brings <resolv.h>, whose `_res` macro breaks Eigen's
// parameter names when Eigen comes after it.
#include "omniloc/live_view.hpp"

#include <httplib.h>

#include <netdb.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace omniloc::live {

namespace {

using Clock = std::chrono::steady_clock;

void close_connection(socket_t sock) {
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
}

// Waits up to `ms` for `events` on the socket: true when it came (or the peer hung up or failed).
bool wait_for(socket_t sock, short events, int ms) {
  pollfd p{sock, events, 0};
  for (;;) {
    const int n = ::poll(&p, 1, ms);
    if (n >= 0) return n > 0;
    if (errno != EINTR) return false;
  }
}

// A connection as httplib reads and writes it (its own SocketStream is not in Debian's header),
// with the server's read and write timeouts on every wait and a small read buffer.
class ConnectionStream final : public httplib::Stream {
 public:
  ConnectionStream(socket_t sock, int read_ms, int write_ms)
      : sock_(sock), read_ms_(read_ms), write_ms_(write_ms) {}
  bool is_readable() const override { return off_ < len_ || wait_for(sock_, POLLIN, read_ms_); }
  bool is_writable() const override { return wait_for(sock_, POLLOUT, write_ms_); }
  ssize_t read(char* ptr, size_t size) override {
    if (off_ == len_) {
      if (!wait_for(sock_, POLLIN, read_ms_)) return -1;
      const ssize_t n = ::recv(sock_, buf_.data(), buf_.size(), 0);
      if (n <= 0) return n;
      off_ = 0;
      len_ = static_cast<std::size_t>(n);
    }
    const std::size_t k = std::min(size, len_ - off_);
    std::memcpy(ptr, buf_.data() + off_, k);
    off_ += k;
    return static_cast<ssize_t>(k);
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (!is_writable()) return -1;
    return ::send(sock_, ptr, size, MSG_NOSIGNAL);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    address(::getpeername, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    address(::getsockname, ip, port);
  }
  socket_t socket() const override { return sock_; }

 private:
  void address(int (*get)(int, sockaddr*, socklen_t*), std::string& ip, int& port) const {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    std::array<char, NI_MAXHOST> host{};
    std::array<char, NI_MAXSERV> serv{};
    if (get(sock_, reinterpret_cast<sockaddr*>(&a), &len) != 0 ||
        ::getnameinfo(reinterpret_cast<sockaddr*>(&a), len, host.data(), host.size(), serv.data(),
                      serv.size(), NI_NUMERICHOST | NI_NUMERICSERV) != 0)
      return;
    ip = host.data();
    port = std::atoi(serv.data());
  }

  socket_t sock_;
  int read_ms_, write_ms_;
  std::array<char, 4096> buf_{};
  std::size_t off_ = 0, len_ = 0;
};

// Connections that have sent nothing yet: one thread polls them all and hands each one with bytes
// to read (or hung up) to `ready`; one idle for the timeout, or the oldest when `capacity` wait
// already, is closed.
class WaitingRoom {
 public:
  WaitingRoom(std::size_t capacity, int timeout_ms, std::function<void(socket_t)> ready)
      : capacity_(std::max<std::size_t>(capacity, 1)),
        timeout_(std::chrono::milliseconds(std::max(timeout_ms, 1))),
        ready_(std::move(ready)),
        wake_(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
    if (wake_ < 0) throw std::runtime_error("live view: eventfd: " + std::string(strerror(errno)));
    thread_ = std::thread([this] { run(); });
  }
  ~WaitingRoom() { stop(); }
  WaitingRoom(const WaitingRoom&) = delete;
  WaitingRoom& operator=(const WaitingRoom&) = delete;

  void add(socket_t sock) {
    const std::lock_guard lock(mutex_);
    if (stopping_) {
      close_connection(sock);
      return;
    }
    if (waiting_.size() >= capacity_) {
      close_connection(waiting_.front().sock);
      waiting_.pop_front();
    }
    waiting_.push_back({sock, Clock::now() + timeout_});
    wake();
  }

  // Stops the thread and closes every connection still waiting.
  void stop() {
    if (!thread_.joinable()) return;
    {
      const std::lock_guard lock(mutex_);
      stopping_ = true;
      wake();
    }
    thread_.join();
    for (const auto& w : waiting_) close_connection(w.sock);
    waiting_.clear();
    ::close(wake_);
  }

 private:
  struct Waiting {
    socket_t sock;
    Clock::time_point deadline;
  };

  void wake() const {
    const std::uint64_t one = 1;
    (void)!::write(wake_, &one, sizeof one);
  }

  // The sockets to poll (the wake-up first) and how long until the oldest runs out; false: stop.
  bool snapshot(std::vector<pollfd>& fds, int& timeout_ms) {
    const std::lock_guard lock(mutex_);
    if (stopping_) return false;
    fds.assign(1, pollfd{wake_, POLLIN, 0});
    for (const auto& w : waiting_) fds.push_back({w.sock, POLLIN, 0});
    timeout_ms = -1;
    if (!waiting_.empty()) {
      const auto left =
          std::chrono::ceil<std::chrono::milliseconds>(waiting_.front().deadline - Clock::now());
      timeout_ms = static_cast<int>(std::max<std::int64_t>(left.count(), 0));
    }
    return true;
  }

  // Takes out the ready sockets and closes the ones past their time; returns the ready ones. Only
  // sockets still waiting are handed on: one closed for a newer one meanwhile is no longer ours.
  std::vector<socket_t> sort_out(const std::vector<pollfd>& fds) {
    std::vector<socket_t> polled, ready;
    for (std::size_t i = 1; i < fds.size(); ++i)
      if (fds[i].revents != 0) polled.push_back(fds[i].fd);
    const std::lock_guard lock(mutex_);
    std::erase_if(waiting_, [&](const Waiting& w) {
      if (std::find(polled.begin(), polled.end(), w.sock) == polled.end()) return false;
      ready.push_back(w.sock);
      return true;
    });
    const auto now = Clock::now();
    while (!waiting_.empty() && waiting_.front().deadline <= now) {
      close_connection(waiting_.front().sock);
      waiting_.pop_front();
    }
    return ready;
  }

  void run() {
    std::vector<pollfd> fds;
    int timeout_ms = -1;
    while (snapshot(fds, timeout_ms)) {
      if (::poll(fds.data(), fds.size(), timeout_ms) < 0 && errno != EINTR) break;
      std::uint64_t n = 0;
      if (fds[0].revents != 0) (void)!::read(wake_, &n, sizeof n);
      for (const socket_t s : sort_out(fds)) ready_(s);
    }
  }

  const std::size_t capacity_;
  const Clock::duration timeout_;
  const std::function<void(socket_t)> ready_;
  const int wake_;
  std::mutex mutex_;
  std::deque<Waiting> waiting_;  // oldest first
  bool stopping_ = false;
  std::thread thread_;
};

void no_cache(httplib::Response& res) {
  res.set_header("Cache-Control", "no-store");
}

int to_ms(time_t sec, time_t usec) {
  return static_cast<int>(sec * 1000 + usec / 1000);
}

// httplib's server with the waiting room in front of four workers: the accept loop's queue runs
// the hand-over at once (process_and_close_socket only files the socket in the waiting room), the
// waiting room hands a connection with bytes to read to the workers, and they serve its one
// request with the read and write timeouts.
class GuardedServer final : public httplib::Server {
 public:
  explicit GuardedServer(const LiveViewOptions& o)
      : room_(static_cast<std::size_t>(std::max(o.max_waiting_connections, 1)),
              o.first_byte_timeout_ms,
              [this](socket_t s) { workers_.enqueue([this, s] { serve(s); }); }) {
    new_task_queue = [] { return new AtOnce; };
  }
  ~GuardedServer() override {
    room_.stop();
    workers_.shutdown();
  }
  GuardedServer(const GuardedServer&) = delete;
  GuardedServer& operator=(const GuardedServer&) = delete;

  // httplib listens with a backlog of 5: beyond it the kernel drops connections before they are
  // accepted (the client retries after 1 s, 3 s, ...), so a few idle ones would delay the page
  // before it reached the waiting room. Listening again on the bound socket widens it.
  bool widen_backlog(int backlog) { return ::listen(svr_sock_, backlog) == 0; }

 private:
  struct AtOnce final : httplib::TaskQueue {
    void enqueue(std::function<void()> fn) override { fn(); }
    void shutdown() override {}
  };
  bool process_and_close_socket(socket_t sock) override {
    room_.add(sock);
    return true;
  }
  void serve(socket_t sock) {
    ConnectionStream strm(sock, to_ms(read_timeout_sec_, read_timeout_usec_),
                          to_ms(write_timeout_sec_, write_timeout_usec_));
    bool closed = false;
    process_request(strm, true, closed, nullptr);
    close_connection(sock);
  }

  httplib::ThreadPool workers_{4};
  WaitingRoom room_;
};

// The server's limits: short timeouts once a request started, small requests (the page only
// GETs), and the port never shared with another daemon.
void configure(httplib::Server& s) {
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

struct LiveViewServer::Impl {
  explicit Impl(const LiveViewOptions& options) : server(options) {}
  GuardedServer server;
  std::thread thread;
  std::atomic<bool> finished{false};
  int port = 0;
};

LiveViewServer::LiveViewServer(LiveState& state, const LiveViewOptions& options)
    : impl_(std::make_unique<Impl>(options)) {
  GuardedServer& s = impl_->server;
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
  if (!s.widen_backlog(std::max(options.max_waiting_connections, SOMAXCONN)))
    throw std::runtime_error(where + ": listen: " + std::strerror(errno));
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
