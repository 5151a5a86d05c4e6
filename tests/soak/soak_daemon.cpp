// Daemon soak: omnilocd's Daemon on the simulated robot (as omnilocd-sim runs it) for a long
// stretch of simulated time, as fast as the simulation goes, with faults injected on a schedule:
//   - the board unplugged and plugged back (the link throws kDeviceGone, reopening fails with
//     kNotFound, what the board sends meanwhile is lost),
//   - the camera stalling (no frame delivered),
//   - a burst of corrupt bytes on the link (each byte read xor-ed with a random non-zero mask at
//     a rate of 1 in 3),
//   - the disk filling up under the recording (a file size limit, RLIMIT_FSIZE with SIGXFSZ
//     ignored, set to the size encoders.csv has at that moment: its next write fails with
//     "File too large" as on a full disk; lifted again 2 s later),
// every 30 s of simulated time: unplug 5.0-6.5 s, camera stall 12-14 s, corrupt burst 20.0-20.3 s
// into each cycle; the disk fills once, 25 s into the cycle holding 70 % of the run.
//
// The poses are received on a UDP socket of its own (the datagrams as any consumer gets them) and
// checked as they arrive: seq gaps (lost datagrams), gaps in time (consecutive datagrams more than
// 20 ms of daemon time apart) and, for every fault, that it was noticed (degraded while unplugged,
// odometry_only while the camera stalls, the recording stopped) and survived (a datagram with
// status ok within 5 s of its end). At the end the recording is replayed with `omniloc replay` and
// its replayable span is compared with the time the disk filled. RSS (VmRSS) is read at 10 s of
// simulated time (after the warm-up) and at the end. Prints the figures; exits 1 when a check
// fails.
//
//   soak_daemon [--minutes M | --duration-s S] [--board reference|verilated] [--camera-fps F]
//               [--seed N] [--out DIR] [--max-rss-growth-mb MB]
//
// --board verilated is what omnilocd-sim runs (the Verilated RTL at 12 MHz: ~1.5 CPU-s per
// simulated second on this machine); reference (default) is the C++ golden model of the board's
// protocol behind the same Transport interface (sim/include/omniloc_sim/reference_board.hpp), fast
// enough for an hour of simulated time in minutes. docs/TESTING.md "Daemon soak".
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "../host/udp_receiver.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/recording.hpp"
#include "omniloc_sim/playing_area.hpp"
#include "omniloc_sim/reference_board.hpp"
#include "omniloc_sim/sim_daemon.hpp"
#include "omniloc_sim/sim_robot.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "omniloc_sim/world.hpp"

#ifndef OMNILOC_CLI_PATH
#error "OMNILOC_CLI_PATH (the omniloc program, for `omniloc replay`) must be defined"
#endif

namespace {

using namespace omniloc;
using namespace omniloc::daemon;
namespace fs = std::filesystem;

constexpr double kWindowMs = 10.0;
constexpr double kCycleMs = 30'000.0;
constexpr double kResumeWithinMs = 5'000.0;
constexpr double kGapMs = 20.0;
constexpr double kMaxBurstGapMs =
    250.0 + 2 * kWindowMs;  // the daemon's board-silence timeout, + a window each side

struct Options {
  double duration_s = 3600.0;
  std::string board = "reference";
  double camera_fps = 15.0;
  std::uint64_t seed = 1;
  std::string out = "soak-daemon";
  double max_rss_growth_mb = 16.0;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto text = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    auto number = [&]() -> double {
      const std::string v = text();
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !std::isfinite(x))
        throw std::invalid_argument(a + ": not a number: '" + v + "'");
      return x;
    };
    if (a == "--minutes")
      o.duration_s = 60.0 * number();
    else if (a == "--duration-s")
      o.duration_s = number();
    else if (a == "--board")
      o.board = text();
    else if (a == "--camera-fps")
      o.camera_fps = number();
    else if (a == "--seed")
      o.seed = static_cast<std::uint64_t>(number());
    else if (a == "--out")
      o.out = text();
    else if (a == "--max-rss-growth-mb")
      o.max_rss_growth_mb = number();
    else
      throw std::invalid_argument(
          "unknown option '" + a +
          "' (--minutes M | --duration-s S, --board reference|verilated, --camera-fps F, "
          "--seed N, --out DIR, --max-rss-growth-mb MB)");
  }
  if (!(o.duration_s >= 60.0 && o.duration_s <= 86400.0))
    throw std::invalid_argument(
        "--duration-s / --minutes: the run must last 60 s .. 24 h of simulated time");
  if (o.board != "reference" && o.board != "verilated")
    throw std::invalid_argument("--board: 'reference' or 'verilated', got '" + o.board + "'");
  if (!(o.camera_fps >= 1.0 && o.camera_fps <= 60.0))
    throw std::invalid_argument("--camera-fps must be 1 .. 60");
  if (!(o.max_rss_growth_mb > 0.0)) throw std::invalid_argument("--max-rss-growth-mb must be > 0");
  return o;
}

// ---------------------------------------------------------------- schedule

enum class FaultKind { kUnplug, kCameraStall, kCorruptBurst, kDiskFull };
const char* fault_name(FaultKind k) {
  switch (k) {
    case FaultKind::kUnplug:
      return "board unplugged";
    case FaultKind::kCameraStall:
      return "camera stall";
    case FaultKind::kCorruptBurst:
      return "corrupt bytes on the link";
    case FaultKind::kDiskFull:
      return "disk full under the recording";
  }
  return "?";
}

struct Fault {
  FaultKind kind;
  double from_ms, to_ms;
  bool noticed = false;      // its effect showed in the stream (or the report)
  double resumed_ms = -1.0;  // first datagram with status ok after to_ms
  [[nodiscard]] bool active(double t) const { return t >= from_ms && t < to_ms; }
};

std::vector<Fault> make_schedule(double duration_ms) {
  std::vector<Fault> f;
  for (double c = 0.0; c + kCycleMs <= duration_ms + 1e-6; c += kCycleMs) {
    f.push_back({FaultKind::kUnplug, c + 5'000.0, c + 6'500.0});
    f.push_back({FaultKind::kCameraStall, c + 12'000.0, c + 14'000.0});
    f.push_back({FaultKind::kCorruptBurst, c + 20'000.0, c + 20'300.0});
  }
  const double disk_cycle = std::floor(0.7 * duration_ms / kCycleMs) * kCycleMs;
  f.push_back({FaultKind::kDiskFull, disk_cycle + 25'000.0, disk_cycle + 25'000.0});
  // Every fault must leave time to see the stream resume.
  std::erase_if(f, [&](const Fault& x) { return x.to_ms + kResumeWithinMs > duration_ms; });
  return f;
}

struct Faults {
  std::vector<Fault> list;
  [[nodiscard]] bool any(FaultKind k, double t) const {
    return std::any_of(list.begin(), list.end(),
                       [&](const Fault& f) { return f.kind == k && f.active(t); });
  }
};

// ---------------------------------------------------------------- fault injection

/// Any board's transport, unplugged and corrupted on the schedule (daemon time from the clock).
class FaultyTransport final : public Transport {
 public:
  FaultyTransport(std::unique_ptr<Transport> inner, const Faults& faults, DaemonClock& clock,
                  std::mt19937_64& rng, std::uint64_t& corrupted)
      : inner_(std::move(inner)),
        faults_(faults),
        clock_(clock),
        rng_(rng),
        corrupted_(corrupted) {}
  void write(std::span<const std::uint8_t> bytes) override {
    check();
    inner_->write(bytes);
  }
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override {
    check();
    const std::size_t n = inner_->read(out, timeout);
    check();
    if (faults_.any(FaultKind::kCorruptBurst, clock_.now_ms())) {
      std::uniform_int_distribution<int> one_in_3(0, 2), mask(1, 255);
      for (std::size_t i = 0; i < n; ++i) {
        if (one_in_3(rng_) == 0) {
          out[i] = static_cast<std::uint8_t>(out[i] ^ mask(rng_));
          ++corrupted_;
        }
      }
    }
    return n;
  }
  [[nodiscard]] TransportStatus status() const override { return inner_->status(); }
  [[nodiscard]] std::chrono::steady_clock::time_point now() const override { return inner_->now(); }

 private:
  void check() const {
    if (faults_.any(FaultKind::kUnplug, clock_.now_ms()))
      throw TransportError(TransportErrorKind::kDeviceGone, "soak: board unplugged");
  }
  std::unique_ptr<Transport> inner_;
  const Faults& faults_;
  DaemonClock& clock_;
  std::mt19937_64& rng_;
  std::uint64_t& corrupted_;
};

/// A camera that delivers nothing while stalled (its frames are lost, as from a hung driver).
class StallingCamera final : public FrameSource {
 public:
  StallingCamera(FrameSource& inner, const Faults& faults) : inner_(inner), faults_(faults) {}
  std::optional<CameraFrame> poll(double now_ms) override {
    std::optional<CameraFrame> f = inner_.poll(now_ms);
    if (faults_.any(FaultKind::kCameraStall, now_ms)) return std::nullopt;
    return f;
  }
  [[nodiscard]] std::string describe() const override {
    return inner_.describe() + " (stalls on a schedule)";
  }

 private:
  FrameSource& inner_;
  const Faults& faults_;
};

// ---------------------------------------------------------------- the reference-board robot

/// World + the C++ reference board + truth log, advanced by the daemon's clock; while the board is
/// unplugged what it sends is lost.
struct ReferenceRobot {
  sim::World world;
  sim::SimTruthLog log;
  sim::ReferenceBoard board;
  const Faults& faults;
  double now_ms = 0.0;
  std::int64_t windows_run = 0;

  static sim::ReferenceBoardConfig board_config() {
    sim::ReferenceBoardConfig c;
    c.keep_history =
        false;  // hours of frames would otherwise be kept for tests that read them back
    return c;
  }
  ReferenceRobot(const sim::WorldConfig& wc, sim::Trajectory trajectory, const Faults& f)
      : world(wc, std::move(trajectory)),
        board(board_config(),
              [this](std::uint32_t) {
                const sim::SimWindow w = world.next_window();
                log.add(static_cast<double>(windows_run) * kWindowMs, w.truth,
                        w.window.gyro_yaw_deg);
                return w.window.counts;
              }),
        faults(f) {}

  void advance_to(double t_ms) {
    while (static_cast<double>(windows_run + 1) * kWindowMs <= t_ms) {
      ++windows_run;
      board.run_windows(1);
      if (faults.any(FaultKind::kUnplug, static_cast<double>(windows_run) * kWindowMs)) {
        std::uint8_t sink[512];
        while (board.from_board(sink) > 0) {
        }
      }
    }
    now_ms = std::max(now_ms, t_ms);
  }
};

class ReferenceClock final : public DaemonClock {
 public:
  explicit ReferenceClock(ReferenceRobot& r) : r_(r) {}
  double now_ms() override { return r_.now_ms; }
  void wait_ms(double ms) override { r_.advance_to(r_.now_ms + std::max(ms, 0.0)); }

 private:
  ReferenceRobot& r_;
};

class ReferenceTransport final : public Transport {
 public:
  explicit ReferenceTransport(ReferenceRobot& r) : r_(r) {}
  void write(std::span<const std::uint8_t> bytes) override { r_.board.to_board(bytes); }
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override {
    const double deadline = r_.now_ms + static_cast<double>(timeout.count());
    for (;;) {
      const std::size_t n = r_.board.from_board(out);
      if (n > 0) return n;
      if (r_.now_ms >= deadline) return 0;
      // A window's bytes appear when it is captured: on to the next window edge (or the deadline).
      r_.advance_to(std::min(static_cast<double>(r_.windows_run + 1) * kWindowMs, deadline));
    }
  }
  [[nodiscard]] TransportStatus status() const override {
    return {true, false, "reference board (C++ model)", {}};
  }
  [[nodiscard]] std::chrono::steady_clock::time_point now() const override {
    return std::chrono::steady_clock::time_point(
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
            std::chrono::duration<double, std::milli>(r_.now_ms)));
  }

 private:
  ReferenceRobot& r_;
};

/// Random legs over the playing area for the whole run (the simulator's random walk is 25 s long).
sim::Trajectory long_random_walk(std::uint64_t seed, const sim::PlayingArea& f, double duration_s) {
  const double margin = f.robot_half_size_cm + 20.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(f.x_min_cm + margin, f.x_max_cm - margin);
  std::uniform_real_distribution<double> uy(f.y_min_cm + margin, f.y_max_cm - margin);
  std::uniform_real_distribution<double> uyaw(-180.0, 180.0);
  std::uniform_real_distribution<double> uspeed(40.0, 120.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  sim::Trajectory t("soak_random_walk", {f.centre_x_cm(), f.centre_y_cm(), 0.0});
  while (t.duration_s() < duration_s + 1.0) {
    const sim::MotionLimits lim{uspeed(rng), 250.0, 60.0 + 100.0 * u01(rng), 360.0};
    const double pick = u01(rng);
    if (pick < 0.1)
      t.rotate_by(uyaw(rng), lim);
    else if (pick < 0.15)
      t.wait(0.2 + 0.5 * u01(rng));
    else {
      const double yaw = uyaw(rng);  // before the point: the order gcc took as arguments
      t.line_to({ux(rng), uy(rng)}, yaw, lim);
    }
  }
  return t;
}

// ---------------------------------------------------------------- measurements

double rss_mb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;
  }
  return -1.0;
}

/// The pose stream as a consumer sees it, checked datagram by datagram (nothing kept per datagram,
/// so that an hour's run does not grow with the stream).
struct StreamStats {
  std::uint64_t received = 0;
  std::uint64_t unparsable = 0;
  std::uint64_t seq_lost = 0;  // datagrams missing by seq
  std::uint64_t seq_backwards = 0;
  std::uint64_t time_gaps = 0;  // consecutive datagrams more than kGapMs apart (daemon time)
  std::uint64_t gaps_outside_bursts = 0;  // of them, not during a corrupt burst's link silence
  double longest_gap_ms = 0.0;
  std::vector<std::pair<double, double>> first_gaps;  // (time, length) of the first 10 gaps
  std::uint64_t last_seq = 0;
  double last_t_ms = -1.0;
  std::uint64_t ok = 0, degraded = 0, odometry_only = 0, lost = 0, other = 0;
};

void take_datagram(std::string_view text, StreamStats& s, std::vector<Fault>& faults) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    ++s.unparsable;
    return;
  }
  if (!j.is_object() || !j.contains("seq") || !j.contains("t_ms") || !j.contains("status") ||
      !j["seq"].is_number_unsigned() || !j["t_ms"].is_number() || !j["status"].is_string()) {
    ++s.unparsable;
    return;
  }
  const auto seq = j["seq"].get<std::uint64_t>();
  const double t = j["t_ms"].get<double>();
  const std::string status = j["status"].get<std::string>();
  // seq counts from 1.
  if (seq > s.last_seq + 1) s.seq_lost += seq - s.last_seq - 1;
  if (seq <= s.last_seq) ++s.seq_backwards;
  if (s.received > 0) {
    const double gap = t - s.last_t_ms;
    if (gap > kGapMs) {
      ++s.time_gaps;
      if (s.first_gaps.size() < 10) s.first_gaps.emplace_back(s.last_t_ms, gap);
      // A burst silences the link: windows are lost, and after kBoardSilentMs without one the
      // daemon declares the board gone and sends degraded datagrams (docs/DAEMON.md).
      const bool in_burst = std::any_of(faults.begin(), faults.end(), [&](const Fault& f) {
        return f.kind == FaultKind::kCorruptBurst && s.last_t_ms >= f.from_ms - kWindowMs &&
               s.last_t_ms < f.to_ms;
      });
      if (!in_burst) ++s.gaps_outside_bursts;
    }
    s.longest_gap_ms = std::max(s.longest_gap_ms, gap);
  }
  ++s.received;
  s.last_seq = seq;
  s.last_t_ms = t;
  if (status == "ok")
    ++s.ok;
  else if (status == "degraded")
    ++s.degraded;
  else if (status == "odometry_only")
    ++s.odometry_only;
  else if (status == "lost")
    ++s.lost;
  else
    ++s.other;
  for (Fault& f : faults) {
    if (f.kind == FaultKind::kUnplug && f.active(t) && status == "degraded") f.noticed = true;
    if (f.kind == FaultKind::kCameraStall && f.active(t) && status == "odometry_only")
      f.noticed = true;
    if (f.resumed_ms < 0 && t >= f.to_ms && status == "ok") f.resumed_ms = t;
  }
}

/// Last pose time of `omniloc replay` over the recording (-1 when it fails), its stdout kept.
double replay(const fs::path& rec, std::string& output) {
  const fs::path poses = rec.parent_path() / "replayed_poses.csv";
  const std::string cmd = std::string("'") + OMNILOC_CLI_PATH + "' replay '" + rec.string() +
                          "' --out '" + poses.string() + "' 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (p == nullptr) return -1.0;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p) != nullptr) output += buf;
  if (::pclose(p) != 0) return -1.0;
  const std::vector<LocalizedPose> rows = read_poses_csv(poses);
  return rows.empty() ? -1.0 : rows.back().t_ms;
}

int run(const Options& o) {
  std::signal(SIGXFSZ, SIG_IGN);  // the file size limit makes write(2) fail with EFBIG instead
  const double duration_ms = o.duration_s * 1000.0;
  Faults faults{make_schedule(duration_ms)};
  const fs::path out = fs::absolute(o.out);
  const fs::path rec = out / "rec";
  fs::create_directories(out);
  fs::remove_all(rec);

  DaemonConfig cfg;
  cfg.camera_fps = o.camera_fps;
  cfg.udp_address = "127.0.0.1";
  test::UdpReceiver sink;  // the tests' receiver: non-blocking, 8 MB of buffer, a free port
  if (sink.port() == 0)
    throw std::runtime_error(std::string("soak: UDP socket on 127.0.0.1: ") + std::strerror(errno));
  cfg.udp_port = sink.port();
  cfg.control_port = 0;
  cfg.record_dir = rec.string();
  cfg.reconnect_period_ms = 200;
  cfg.status_period_s = 30.0;
  cfg.duration_s = o.duration_s;
  std::printf(
      "soak: %.0f s of simulated time, %s board, camera %.0f fps, seed %llu, %zu faults scheduled, "
      "output %s\n",
      o.duration_s, o.board.c_str(), o.camera_fps, static_cast<unsigned long long>(o.seed),
      faults.list.size(), out.c_str());
  std::fflush(stdout);
  const DaemonModels models = load_models(cfg);
  const sim::PlayingArea area = sim::playing_area(models.field);
  std::mt19937_64 rng(o.seed ^ 0x50a4ULL);
  std::uint64_t corrupted = 0;

  // The robot: either board, its camera, clock, heading and truth.
  std::unique_ptr<sim::SimulatedRobot> verilated;
  std::unique_ptr<ReferenceRobot> reference;
  std::unique_ptr<ReferenceClock> reference_clock;
  std::unique_ptr<sim::OmniRenderer> renderer;
  std::unique_ptr<sim::SimCamera> reference_camera;
  DaemonIo io;
  const sim::SimTruthLog* truth = nullptr;
  sim::Trajectory trajectory = long_random_walk(o.seed, area, o.duration_s);
  if (o.board == "verilated") {
    sim::SimRobotOptions so;
    so.seed = o.seed;
    so.camera_fps = o.camera_fps;
    verilated = std::make_unique<sim::SimulatedRobot>(models, std::move(trajectory), so);
    io = verilated->io();
    truth = &verilated->truth();
  } else {
    reference = std::make_unique<ReferenceRobot>(
        sim::WorldConfig::default_noise(models.robot, o.seed, area), std::move(trajectory), faults);
    reference_clock = std::make_unique<ReferenceClock>(*reference);
    renderer = std::make_unique<sim::OmniRenderer>(models.field, models.camera);
    sim::RenderOptions ro;
    ro.seed = o.seed;
    reference_camera =
        std::make_unique<sim::SimCamera>(*renderer, reference->log, o.camera_fps, ro);
    io.clock = reference_clock.get();
    ReferenceRobot* r = reference.get();
    io.open_board = [r]() -> std::unique_ptr<Transport> {
      return std::make_unique<ReferenceTransport>(*r);
    };
    io.camera = reference_camera.get();
    io.heading = &reference->log;
    truth = &reference->log;
  }
  DaemonClock& clock = *io.clock;
  const TransportFactory inner_factory = io.open_board;
  io.open_board = [&]() -> std::unique_ptr<Transport> {
    if (faults.any(FaultKind::kUnplug, clock.now_ms()))
      throw TransportError(TransportErrorKind::kNotFound, "soak: no board on the bus (unplugged)");
    return std::make_unique<FaultyTransport>(inner_factory(), faults, clock, rng, corrupted);
  };
  StallingCamera camera(*io.camera, faults);
  io.camera = &camera;
  io.logger = Logger(LogLevel::kInfo, Logger::stderr_sink("soak_daemon"));

  Daemon d(cfg, models, io);
  TruthCsvWriter truth_csv(rec / "truth.csv");
  StreamStats stream;
  double rss_start = -1.0, rss_max = 0.0;
  struct rlimit unlimited {};
  ::getrlimit(RLIMIT_FSIZE, &unlimited);
  double disk_full_at_ms = -1.0, disk_limit_bytes = 0.0;
  bool limit_lifted = false;
  DaemonObserver observer;
  observer.on_window = sim::truth_recorder(*truth, truth_csv);
  observer.on_loop = [&](double now) {
    for (const std::string& s : sink.drain()) take_datagram(s, stream, faults.list);
    if (rss_start < 0 && now >= 10'000.0) rss_start = rss_mb();
    if (static_cast<std::int64_t>(now) % 1000 < 10) rss_max = std::max(rss_max, rss_mb());
    for (const Fault& f : faults.list) {
      if (f.kind != FaultKind::kDiskFull || disk_full_at_ms >= 0 || now < f.from_ms) continue;
      std::error_code ec;
      const auto size = fs::file_size(rec / "encoders.csv", ec);
      struct rlimit lim = unlimited;
      lim.rlim_cur = ec ? 0 : static_cast<rlim_t>(size);
      ::setrlimit(RLIMIT_FSIZE, &lim);
      disk_full_at_ms = now;
      disk_limit_bytes = static_cast<double>(lim.rlim_cur);
    }
    if (disk_full_at_ms >= 0 && !limit_lifted && now >= disk_full_at_ms + 2000.0) {
      ::setrlimit(RLIMIT_FSIZE, &unlimited);
      limit_lifted = true;
    }
  };
  d.set_observer(std::move(observer));
  volatile std::sig_atomic_t stop = 0;
  const DaemonReport r = d.run(&stop);
  ::setrlimit(RLIMIT_FSIZE, &unlimited);
  truth_csv.close();
  for (const std::string& s : sink.drain()) take_datagram(s, stream, faults.list);
  const double rss_end = rss_mb();
  rss_max = std::max(rss_max, rss_end);

  // The disk-full fault: noticed when the recording stopped; survived as any other.
  for (Fault& f : faults.list) {
    if (f.kind == FaultKind::kDiskFull) f.noticed = r.recording_failures >= 1;
    if (f.kind == FaultKind::kCorruptBurst) f.noticed = corrupted > 0 && r.bad_crc > 0;
  }
  std::string replay_output;
  const double replayed_to_ms = replay(rec, replay_output);

  // ---- report
  std::printf("%s\n", report_line(r).c_str());
  std::printf(
      "poses: %llu datagrams received (%llu sent), %llu lost by seq, %llu out of order, %llu "
      "unparsable; "
      "%llu gaps > %.0f ms (longest %.0f ms); ok %llu, degraded %llu, odometry_only %llu, lost "
      "%llu, other %llu\n",
      static_cast<unsigned long long>(stream.received),
      static_cast<unsigned long long>(r.published),
      static_cast<unsigned long long>(stream.seq_lost),
      static_cast<unsigned long long>(stream.seq_backwards),
      static_cast<unsigned long long>(stream.unparsable),
      static_cast<unsigned long long>(stream.time_gaps), kGapMs, stream.longest_gap_ms,
      static_cast<unsigned long long>(stream.ok), static_cast<unsigned long long>(stream.degraded),
      static_cast<unsigned long long>(stream.odometry_only),
      static_cast<unsigned long long>(stream.lost), static_cast<unsigned long long>(stream.other));
  std::string gaps;
  for (const auto& [at, len] : stream.first_gaps)
    gaps += " " + std::to_string(static_cast<int>(len)) + " ms at " +
            std::to_string(static_cast<int>(at / 1000.0)) + " s;";
  std::printf("gaps: %llu outside a corrupt burst; first ones:%s\n",
              static_cast<unsigned long long>(stream.gaps_outside_bursts),
              gaps.empty() ? " none" : gaps.c_str());
  std::printf(
      "link: %llu bytes corrupted in %zu bursts; board lost %llu x, back %llu x; %llu bad CRC, "
      "%llu telemetry gaps\n",
      static_cast<unsigned long long>(corrupted),
      static_cast<std::size_t>(
          std::count_if(faults.list.begin(), faults.list.end(),
                        [](const Fault& f) { return f.kind == FaultKind::kCorruptBurst; })),
      static_cast<unsigned long long>(r.board_losses),
      static_cast<unsigned long long>(r.reconnects), static_cast<unsigned long long>(r.bad_crc),
      static_cast<unsigned long long>(r.telemetry_gaps));
  std::printf(
      "memory: RSS %.1f MB at 10 s, %.1f MB at the end (growth %+.1f MB, bound %.0f MB), max %.1f "
      "MB\n",
      rss_start, rss_end, rss_end - rss_start, o.max_rss_growth_mb, rss_max);
  std::printf("recording: disk full at %.1f s (file size limit %.0f bytes); %s; replay: %s\n",
              disk_full_at_ms / 1000.0, disk_limit_bytes,
              r.recording_error.empty() ? "no write error" : r.recording_error.c_str(),
              replayed_to_ms < 0
                  ? "FAILED"
                  : ("poses up to " + std::to_string(replayed_to_ms / 1000.0) + " s").c_str());
  std::printf("--- omniloc replay:\n%s---\n", replay_output.c_str());

  std::vector<std::string> failures;
  int survived = 0;
  for (const Fault& f : faults.list) {
    const bool ok = f.noticed && f.resumed_ms >= 0 && f.resumed_ms <= f.to_ms + kResumeWithinMs;
    survived += ok ? 1 : 0;
    if (!ok) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "%s at %.1f-%.1f s: %s", fault_name(f.kind),
                    f.from_ms / 1000.0, f.to_ms / 1000.0,
                    !f.noticed         ? "never showed in the stream or the report"
                    : f.resumed_ms < 0 ? "the stream never came back to ok"
                                       : "ok again only after more than 5 s");
      failures.emplace_back(buf);
    }
  }
  std::printf("faults: %d of %zu survived (noticed, then status ok within %.0f s of the end)\n",
              survived, faults.list.size(), kResumeWithinMs / 1000.0);
  auto require = [&](bool ok, const std::string& what) {
    if (!ok) failures.push_back(what);
  };
  require(r.stop_reason == "duration",
          "the run stopped for '" + r.stop_reason + "', not its duration");
  require(stream.unparsable == 0 && stream.seq_backwards == 0,
          "unparsable or out-of-order datagrams");
  require(stream.received + stream.seq_lost == r.published && stream.seq_lost == 0,
          "datagrams lost on the loopback (received + lost by seq != sent, or lost > 0)");
  require(stream.gaps_outside_bursts == 0,
          "a gap in the pose stream (> 20 ms) outside a corrupt burst");
  require(stream.longest_gap_ms <= kMaxBurstGapMs,
          "a gap in the pose stream longer than the board-silence timeout (250 ms) + a window");
  require(stream.received >= static_cast<std::uint64_t>(0.99 * duration_ms / kWindowMs),
          "fewer datagrams than 99 % of one per 10 ms");
  require(rss_start > 0 && rss_end - rss_start <= o.max_rss_growth_mb, "RSS grew beyond the bound");
  require(r.recording_failures == 1,
          "the recording did not stop exactly once at the disk-full point");
  require(replayed_to_ms >= disk_full_at_ms - 2000.0 && replayed_to_ms <= disk_full_at_ms + 1000.0,
          "the recording does not replay up to the disk-full point (-2 s .. +1 s)");
  for (const std::string& f : failures) std::printf("soak: FAILED: %s\n", f.c_str());
  if (failures.empty()) std::printf("soak: OK\n");
  return failures.empty() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soak_daemon: %s\n", e.what());
    return 2;
  }
}
