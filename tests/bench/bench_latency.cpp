// Latency through the robot's daemon (issue 15.6), on the simulated robot (Verilated board, the
// rendered camera): for every window, host wall time from the transport handing over the bytes
// that held it (the board's tick plus the line time, which is the link's and not counted) to its
// datagram having left the UDP socket (the observer's on_pose runs right after the send); for every
// camera frame, from the frame source handing it over to the first datagram that used it (below).
// Percentiles over a 10 s drive, beside the reference measured in the same run: the same datagram
// sent alone on a loopback socket (what the path cannot go below), printing the ratio. Targets:
// window p99 below 2 ms, frame below 3 ms. The drive runs twice: with the cross-check's global
// search inline on the frame that triggers it (cross_check_worker false: the code before
// issue 15.6's fix, the reference) and on its worker (the default), the frame path split at the
// localizer having taken the frame (on_image: the lines, and the match when a window already covers
// the frame's time) and the next window's way to its datagram.
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
#include <utility>
#include <vector>

#include "omniloc/daemon.hpp"
#include "omniloc/daemon_publish.hpp"
#include "omniloc/transport.hpp"
#include "omniloc_sim/sim_daemon.hpp"

namespace omniloc {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

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
  TimedCamera(daemon::FrameSource& inner, std::optional<Clock::time_point>& handed)
      : inner_(inner), handed_(handed) {}
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
  const auto at = [&](double q) {
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
  };
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
    (void)::sendto(s, datagram.data(), datagram.size(), 0, reinterpret_cast<sockaddr*>(&a),
                   sizeof a);
    out.push_back(ms_since(t0));
    (void)::recv(r, buf, sizeof buf, 0);
  }
  ::close(s);
  ::close(r);
  return out;
}

struct Run {
  Percentiles window, frame, frame_taken, frame_window;
  std::string datagram;
  std::string report;
};

/// One 10 s drive of the daemon on the simulated robot with `models`.
Run drive(const daemon::DaemonModels& models) {
  daemon::DaemonConfig cfg;
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
  std::vector<double> window_ms, frame_ms, taken_ms, frame_window_ms;
  Run out;
  // A frame's time to the pose: its handover to the localizer having taken it (the line
  // extraction, and the match if a window already covers the frame's time; else the frame waits
  // and is matched with the next window), plus the next window's bytes-in to datagram. The wall
  // time in between is the simulator's, making the board's next 10 ms, which a real robot spends
  // waiting.
  std::optional<double> frame_taken_ms;
  io.observer.on_pose = [&](const daemon::PoseEvent& e) {
    if (!e.from_window || !last_bytes) return;
    const double w = ms_since(*last_bytes);
    window_ms.push_back(w);
    last_bytes.reset();  // a window answered from the same read is not counted twice
    if (frame_taken_ms) {
      frame_ms.push_back(*frame_taken_ms + w);
      taken_ms.push_back(*frame_taken_ms);
      frame_window_ms.push_back(w);
    }
    frame_taken_ms.reset();
    if (out.datagram.empty()) out.datagram = daemon::pose_json(e.message);
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
  out.report = daemon::report_line(rep);
  out.window = percentiles(window_ms);
  out.frame = percentiles(frame_ms);
  out.frame_taken = percentiles(taken_ms);
  out.frame_window = percentiles(frame_window_ms);
  return out;
}

void print_row(const char* name, const Percentiles& p) {
  std::printf("%-58s %8zu %8.3f %8.3f %8.3f\n", name, p.n, p.p50, p.p99, p.max);
}

int run() {
  daemon::DaemonConfig cfg;
  std::printf("loading the models (the feature database from the cache, or built once)...\n");
  daemon::DaemonModels models = daemon::load_models(cfg);
  // The reference, in the same run: the cross-check's global search inline on the frame that
  // triggers it (the code before issue 15.6's fix), then the shipped default (on its worker).
  models.localizer.cross_check_worker = false;
  const Run inline_run = drive(models);
  std::printf("cross-check inline: %s\n", inline_run.report.c_str());
  models.localizer.cross_check_worker = true;
  const Run worker_run = drive(models);
  std::printf("cross-check on its worker: %s\n", worker_run.report.c_str());
  const std::string& gram = worker_run.datagram.empty() ? inline_run.datagram : worker_run.datagram;
  const Percentiles ref =
      percentiles(bare_sends(gram.empty() ? std::string(300, 'x') : gram, 2000));
  std::printf("\n%-58s %8s %8s %8s %8s\n", "latency (ms, host wall clock)", "n", "p50", "p99",
              "max");
  for (const auto& [label, r] :
       {std::pair<const char*, const Run*>{"cross-check inline (before)", &inline_run},
        std::pair<const char*, const Run*>{"cross-check on its worker (now)", &worker_run}}) {
    std::printf("%s:\n", label);
    print_row("  window bytes in -> datagram sent", r->window);
    print_row("  camera frame handed over -> its pose sent", r->frame);
    print_row("    of which: handed over -> taken (on_image: lines, match)", r->frame_taken);
    print_row("    of which: next window's bytes in -> datagram", r->frame_window);
  }
  print_row("reference: the datagram's sendto alone", ref);
  const Run& w = worker_run;
  std::printf("ratio window path / bare send: p50 %.1f x, p99 %.1f x\n", w.window.p50 / ref.p50,
              w.window.p99 / ref.p99);
  std::printf("ratio frame path inline / worker: p50 %.2f x, p99 %.2f x\n",
              inline_run.frame.p50 / w.frame.p50, inline_run.frame.p99 / w.frame.p99);
  std::printf("targets (worker): window p99 %.3f ms (< 2 ms: %s), frame p99 %.3f ms (< 3 ms: %s)\n",
              w.window.p99, w.window.p99 < 2.0 ? "met" : "NOT met", w.frame.p99,
              w.frame.p99 < 3.0 ? "met" : "NOT met");
  return 0;
}

}  // namespace
}  // namespace omniloc

int main() {
  return omniloc::run();
}
