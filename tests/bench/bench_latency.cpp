// Latency through the robot's daemon (issue 15.6), on the simulated robot (Verilated board, the
// rendered camera): for every window, host wall time from the transport handing over the bytes
// that held it (the board's tick plus the line time, which is the link's and not counted) to its
// datagram having left the UDP socket (the observer's on_pose runs right after the send); for every
// camera frame, from the frame source handing it over to the first datagram that used it (below). Percentiles
// over a 10 s drive, beside the reference measured in the same run: the same datagram sent alone on
// a loopback socket (what the path cannot go below), printing the ratio. Targets: window p99 below
// 2 ms, frame below 3 ms.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "omniloc/daemon.hpp"
#include "omniloc/daemon_publish.hpp"
#include "omniloc/transport.hpp"
#include "omniloc_sim/sim_daemon.hpp"

namespace omniloc {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

/// Passes the simulated board through, keeping when its last read returned bytes.
class TimedTransport : public Transport {
 public:
  TimedTransport(std::unique_ptr<Transport> inner, std::optional<Clock::time_point>& last_bytes)
      : inner_(std::move(inner)), last_bytes_(last_bytes) {}
  void write(std::span<const std::uint8_t> bytes) override { inner_->write(bytes); }
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override {
    const std::size_t n = inner_->read(out, timeout);
    if (n > 0) last_bytes_ = Clock::now();
    return n;
  }
  [[nodiscard]] TransportStatus status() const override { return inner_->status(); }
  [[nodiscard]] Clock::time_point now() const override { return inner_->now(); }

 private:
  std::unique_ptr<Transport> inner_;
  std::optional<Clock::time_point>& last_bytes_;
};

/// Passes the simulated camera through, keeping when it handed a frame over.
class TimedCamera : public daemon::FrameSource {
 public:
  TimedCamera(daemon::FrameSource& inner, std::optional<Clock::time_point>& handed) : inner_(inner), handed_(handed) {}
  std::optional<daemon::CameraFrame> poll(double now_ms) override {
    auto f = inner_.poll(now_ms);
    if (f) handed_ = Clock::now();
    return f;
  }
  [[nodiscard]] std::string describe() const override { return inner_.describe(); }

 private:
  daemon::FrameSource& inner_;
  std::optional<Clock::time_point>& handed_;
};

struct Percentiles {
  double p50 = 0, p99 = 0, max = 0;
  std::size_t n = 0;
};
Percentiles percentiles(std::vector<double> v) {
  Percentiles p;
  p.n = v.size();
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))]; };
  p.p50 = at(0.50);
  p.p99 = at(0.99);
  p.max = v.back();
  return p;
}

/// The reference: the daemon's datagram text sent alone on a loopback UDP socket, per send.
std::vector<double> bare_sends(const std::string& datagram, int count) {
  const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
  const int r = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(r, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(r, reinterpret_cast<sockaddr*>(&a), &len);
  std::vector<double> out;
  char buf[2048];
  for (int i = 0; i < count; ++i) {
    const auto t0 = Clock::now();
    (void)::sendto(s, datagram.data(), datagram.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof a);
    out.push_back(ms_since(t0));
    (void)::recv(r, buf, sizeof buf, 0);
  }
  ::close(s);
  ::close(r);
  return out;
}

int run() {
  daemon::DaemonConfig cfg;
  std::printf("loading the models (the feature database from the cache, or built once)...\n");
  const daemon::DaemonModels models = daemon::load_models(cfg);
  sim::SimRobotOptions ro;
  ro.seed = 5;
  sim::SimulatedRobot robot(models, sim::make_trajectory("figure_eight", ro.seed), ro);
  daemon::DaemonIo io = robot.io();
  std::optional<Clock::time_point> last_bytes, handed;
  auto open = io.open_board;
  io.open_board = [open, &last_bytes]() -> std::unique_ptr<Transport> {
    return std::make_unique<TimedTransport>(open(), last_bytes);
  };
  TimedCamera camera(*io.camera, handed);
  io.camera = &camera;
  std::vector<double> window_ms, frame_ms;
  std::string datagram;
  // A frame's time to the pose: its handover to the localizer having taken it (the line
  // extraction), plus the next window's bytes-in to datagram (where the localizer matches the
  // frames it placed before that window). The wall time in between is the simulator's, making the
  // board's next 10 ms, which a real robot spends waiting.
  std::optional<double> frame_taken_ms;
  io.observer.on_pose = [&](const daemon::PoseEvent& e) {
    if (!e.from_window || !last_bytes) return;
    const double w = ms_since(*last_bytes);
    window_ms.push_back(w);
    last_bytes.reset();  // a window answered from the same read is not counted twice
    if (frame_taken_ms) frame_ms.push_back(*frame_taken_ms + w);
    frame_taken_ms.reset();
    if (datagram.empty()) datagram = daemon::pose_json(e.message);
  };
  io.observer.on_frame = [&](const daemon::CameraFrame&) {
    if (handed) frame_taken_ms = ms_since(*handed);
    handed.reset();
  };
  io.logger = Logger(LogLevel::kWarning, [](LogLevel, std::string_view line) {
    std::fprintf(stderr, "%.*s\n", static_cast<int>(line.size()), line.data());
  });
  cfg.udp_address = "127.0.0.1";
  cfg.udp_port = 9;  // discard: nobody listens, the send still leaves the socket
  cfg.duration_s = 10.0;
  daemon::Daemon d(cfg, models, io);
  volatile std::sig_atomic_t stop = 0;
  const daemon::DaemonReport rep = d.run(&stop);
  std::printf("%s\n", daemon::report_line(rep).c_str());
  const Percentiles w = percentiles(window_ms), f = percentiles(frame_ms);
  const Percentiles ref = percentiles(bare_sends(datagram.empty() ? std::string(300, 'x') : datagram, 2000));
  std::printf("\n%-44s %8s %8s %8s %8s\n", "latency (ms, host wall clock)", "n", "p50", "p99", "max");
  std::printf("%-44s %8zu %8.3f %8.3f %8.3f\n", "window bytes in -> datagram sent", w.n, w.p50, w.p99, w.max);
  std::printf("%-44s %8zu %8.3f %8.3f %8.3f\n", "camera frame handed over -> its pose sent", f.n, f.p50, f.p99, f.max);
  std::printf("%-44s %8zu %8.3f %8.3f %8.3f\n", "reference: the datagram's sendto alone", ref.n, ref.p50, ref.p99, ref.max);
  std::printf("ratio window path / bare send: p50 %.1f x, p99 %.1f x\n", w.p50 / ref.p50, w.p99 / ref.p99);
  std::printf("targets: window p99 %.3f ms (< 2 ms: %s), frame p99 %.3f ms (< 3 ms: %s)\n", w.p99,
              w.p99 < 2.0 ? "met" : "NOT met", f.p99, f.p99 < 3.0 ? "met" : "NOT met");
  return 0;
}

}  // namespace
}  // namespace omniloc

int main() { return omniloc::run(); }
