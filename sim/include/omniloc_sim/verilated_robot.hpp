// The simulated robot on the Verilated board, for `omnilocd-sim` and `omniloc-sim demo`: the
// world simulator's quadrature waveforms drive the Verilated rtl/omniloc_top.v (BoardSim) at 12
// MHz, the ICM-42688-P model on its SPI pins measures the world's true yaw rate (with the world
// gyro's bias, scale error and rate noise), the host reaches it through SimTransport, and the
// daemon's heading is the board's gyro windows (GyroHeading), its clock the host clock of the
// simulation (sim_clocks.hpp): the board's simulated time over (1 + board_drift_ppm 1e-6), the
// windows' bytes delivered after a USB latency (DelayedSimTransport). With
// SimClockConfig::perfect() the daemon's clock is the board's time and bytes arrive as the UART
// delivers them. Header-only; programs including it link omniloc_board_sim.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "omniloc/daemon.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "omniloc_sim/encoder_waveform.hpp"
#include "omniloc_sim/icm42688.hpp"
#include "omniloc_sim/sim_clocks.hpp"
#include "omniloc_sim/sim_robot.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::sim {

/// The world at the Verilated board's clock: 1 ms physics steps and 10 ms windows at 12 MHz, the
/// encoders starting at AB = 00 as the board's decoders do after reset.
[[nodiscard]] inline WorldConfig board_world_config(RobotConfig robot, std::uint64_t seed,
                                                    const PlayingArea& area = fira_robosot_area()) {
  auto wc = WorldConfig::default_noise(robot, seed, area);
  wc.set_clock(static_cast<double>(BoardSim::kClockHz));
  wc.random_encoder_phase = false;
  return wc;
}

/// The world's true (unwrapped) yaw at the end of each physics step, in board cycles: the true yaw
/// rate at any recent cycle is the slope of the step that holds it (the world moves linearly within
/// a step). What the gyro model samples. A kidnapping turns the world in one step, which no gyro
/// could follow: a step faster than kMaxCarryDps is spread over the next steps at that rate (the
/// robot carried and turned over a fraction of a second), so the integral stays the true turn.
class YawRateLog {
 public:
  static constexpr double kMaxCarryDps = 1000.0;  ///< half the part's +-2000 deg/s range

  void add(std::int64_t cycle, double yaw_deg) {
    if (!points_.empty() && cycle <= points_.back().cycle) return;
    double apparent = yaw_deg;
    if (!points_.empty()) {
      const double dt_s = static_cast<double>(cycle - points_.back().cycle) /
                          static_cast<double>(BoardSim::kClockHz);
      const double wanted = yaw_deg - last_true_deg_ + carry_deg_;
      const double step = std::clamp(wanted, -kMaxCarryDps * dt_s, kMaxCarryDps * dt_s);
      carry_deg_ = wanted - step;
      apparent = points_.back().yaw_deg + step;
    }
    last_true_deg_ = yaw_deg;
    points_.push_back({cycle, apparent});
    if (points_.size() > 64) points_.pop_front();
  }
  /// deg/s at `cycle` (the newest step's rate beyond the log, 0 before two points).
  [[nodiscard]] double rate_dps(std::int64_t cycle) const {
    if (points_.size() < 2) return 0.0;
    std::size_t i = points_.size() - 1;
    while (i > 1 && points_[i - 1].cycle > cycle) --i;
    const Point& a = points_[i - 1];
    const Point& b = points_[i];
    return (b.yaw_deg - a.yaw_deg) /
           (static_cast<double>(b.cycle - a.cycle) / static_cast<double>(BoardSim::kClockHz));
  }

 private:
  struct Point {
    std::int64_t cycle;
    double yaw_deg;
  };
  std::deque<Point> points_;
  double last_true_deg_ = 0.0;
  double carry_deg_ = 0.0;  ///< turn still to be spread (after a kidnapping)
};

/// Feeds the board the stream's levels and logs the world's truth and gyro after every block
/// (a block of BoardSim is shorter than a physics step, so every step is seen), and the true yaw
/// for the gyro model.
class LoggingQuadratureSource final : public EncoderSource {
 public:
  /// `crystal`: truth is logged in host time (the board's cycles are its own time).
  LoggingQuadratureSource(QuadratureStream& stream, SimTruthLog& log, BoardCrystal crystal = {})
      : stream_(stream), log_(log), crystal_(crystal) {
    yaw_.add(0, stream_.world().truth().yaw_deg);
  }
  void fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out) override {
    stream_.fill_levels(first_cycle, out);
    const World& w = stream_.world();
    constexpr double kCyclesPerMs = static_cast<double>(BoardSim::kClockHz) / 1000.0;
    log_.add(crystal_.host_ms(static_cast<double>(w.cycle()) / kCyclesPerMs), w.truth(),
             w.gyro().report(w.gyro().raw_yaw_deg()));
    yaw_.add(w.cycle(), w.truth().yaw_deg);
  }
  [[nodiscard]] const YawRateLog& yaw() const { return yaw_; }

 private:
  QuadratureStream& stream_;
  SimTruthLog& log_;
  BoardCrystal crystal_;
  YawRateLog yaw_;
};

/// The ICM-42688-P on the simulated board: the world's true yaw rate with the world gyro's bias and
/// scale error, and its angle random walk as white rate noise per sample (ARW x sqrt(ODR)).
[[nodiscard]] inline Icm42688Params board_gyro_params(const World& world) {
  Icm42688Params p;
  p.clk_hz = static_cast<double>(BoardSim::kClockHz);
  p.bias_dps = world.gyro().bias_deg_per_s();
  p.noise_dps_rms =
      world.config().gyro.arw_deg_per_sqrt_s * std::sqrt(static_cast<double>(regmap::kGyroOdrHz));
  p.seed = world.config().seed ^ 0x6F1C0ULL;
  p.keep_logs = false;
  return p;
}

/// Daemon time = the simulation's host clock: the board's simulated time through its crystal
/// (equal to it with a perfect crystal); waiting runs the board.
class BoardSimClock final : public daemon::DaemonClock {
 public:
  explicit BoardSimClock(BoardSim& board, BoardCrystal crystal = {})
      : board_(board), crystal_(crystal) {}
  double now_ms() override { return crystal_.host_ms(board_.seconds() * 1000.0); }
  void wait_ms(double ms) override {
    if (ms > 0)
      board_.run_cycles(static_cast<std::int64_t>(ms * (1.0 + crystal_.drift_ppm * 1e-6) *
                                                  (BoardSim::kClockHz / 1000)));
  }

 private:
  BoardSim& board_;
  BoardCrystal crystal_;
};

/// SimTransport with a USB latency: each chunk of bytes the board sends is released to the host
/// at the arrival time UsbArrivals gives it (host clock), in order. Writes go straight through.
class DelayedSimTransport final : public Transport {
 public:
  DelayedSimTransport(BoardSim& board, daemon::DaemonClock& host, UsbArrivals& usb)
      : board_(board), host_(host), usb_(usb), direct_(board) {}
  void write(std::span<const std::uint8_t> bytes) override { direct_.write(bytes); }
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override {
    constexpr std::int64_t kSlice = BoardSim::kClockHz / 10'000;  // 100 us, as SimTransport
    const std::int64_t deadline = board_.cycle() + timeout.count() * (BoardSim::kClockHz / 1000);
    for (;;) {
      take();
      if (!held_.empty() && held_.front().release_ms <= host_.now_ms()) break;
      if (board_.cycle() >= deadline) return 0;
      board_.run_cycles(kSlice);
    }
    std::size_t n = 0;
    while (n < out.size() && !held_.empty() && held_.front().release_ms <= host_.now_ms()) {
      Chunk& c = held_.front();
      const std::size_t k = std::min(out.size() - n, c.bytes.size() - c.used);
      std::copy_n(c.bytes.begin() + static_cast<std::ptrdiff_t>(c.used), k,
                  out.begin() + static_cast<std::ptrdiff_t>(n));
      n += k;
      c.used += k;
      if (c.used == c.bytes.size()) held_.pop_front();
    }
    counters_.bytes_read += n;
    return n;
  }
  [[nodiscard]] TransportStatus status() const override {
    TransportStatus st = direct_.status();
    st.counters.bytes_read = counters_.bytes_read;
    st.description += ", USB latency simulated";
    return st;
  }
  [[nodiscard]] std::chrono::steady_clock::time_point now() const override { return direct_.now(); }

 private:
  struct Chunk {
    std::vector<std::uint8_t> bytes;
    std::size_t used = 0;
    double release_ms = 0.0;
  };
  void take() {
    std::uint8_t buf[512];
    for (std::size_t n; (n = board_.from_board(buf)) > 0;)
      held_.push_back(
          {std::vector<std::uint8_t>(buf, buf + n), 0, usb_.arrival_ms(host_.now_ms())});
  }
  BoardSim& board_;
  daemon::DaemonClock& host_;
  UsbArrivals& usb_;
  SimTransport direct_;
  std::deque<Chunk> held_;
  TransportCounters counters_;
};

/// Everything of the simulated robot, wired: world -> encoders and gyro -> Verilated board ->
/// transport.
struct VerilatedRobot {
  SimClockConfig clocks;
  QuadratureStream stream;
  SimTruthLog log;
  LoggingQuadratureSource source;
  Icm42688 gyro;
  BoardSim board;
  BoardSimClock clock;
  UsbArrivals usb;

  /// `clocks`: perfect() by default here (SimRobotOptions chooses realistic ones for the daemon).
  VerilatedRobot(const WorldConfig& world, Trajectory trajectory,
                 const SimClockConfig& clock_config = {}, std::uint64_t clock_seed = 1)
      : clocks(clock_config),
        stream(world, std::move(trajectory)),
        source(stream, log, BoardCrystal{clock_config.board_drift_ppm, 0.0}),
        gyro(board_gyro_params(stream.world()),
             [this, scale = 1.0 + stream.world().gyro().scale_error()](double t_s) {
               return scale * source.yaw().rate_dps(static_cast<std::int64_t>(
                                  t_s * static_cast<double>(BoardSim::kClockHz)));
             }),
        board(&source, &gyro),
        clock(board, BoardCrystal{clock_config.board_drift_ppm, 0.0}),
        usb(clock_config, clock_seed) {}

  /// A fresh transport each time (the board itself keeps running, as after a USB replug): the
  /// plain SimTransport with perfect clocks, else one with the USB latency.
  [[nodiscard]] daemon::TransportFactory transport_factory() {
    const bool delayed = clocks.usb_jitter_mean_ms > 0.0 || clocks.burst_every_s > 0.0;
    return [this, delayed]() -> std::unique_ptr<Transport> {
      if (delayed) return std::make_unique<DelayedSimTransport>(board, clock, usb);
      return std::make_unique<SimTransport>(board);
    };
  }
};

}  // namespace omniloc::sim
