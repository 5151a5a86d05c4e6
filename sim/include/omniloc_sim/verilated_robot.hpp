// The simulated robot on the Verilated board, for `omnilocd-sim` and `omniloc-sim demo`: the
// world simulator's quadrature waveforms drive the Verilated rtl/omniloc_top.v (BoardSim) at 12 MHz,
// the host reaches it through SimTransport, and the daemon's clock is the board's simulated time.
// Header-only; programs including it link omniloc_board_sim.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "omniloc/daemon.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "omniloc_sim/encoder_waveform.hpp"
#include "omniloc_sim/sim_robot.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::sim {

/// The world at the Verilated board's clock: 1 ms physics steps and 10 ms windows at 12 MHz, the
/// encoders starting at AB = 00 as the board's decoders do after reset.
[[nodiscard]] inline WorldConfig board_world_config(RobotConfig robot, std::uint64_t seed,
                                                    const PlayingArea& area = fira_robosot_area()) {
  robot.clock_hz = static_cast<double>(BoardSim::kClockHz);
  auto wc = WorldConfig::default_noise(robot, seed, area);
  wc.step_cycles = BoardSim::kClockHz / 1000;
  wc.window_cycles = BoardSim::kClockHz / 100;
  wc.first_window_end_cycles = wc.window_cycles;
  wc.random_encoder_phase = false;
  return wc;
}

/// Feeds the board the stream's levels and logs the world's truth and gyro after every block
/// (a block of BoardSim is shorter than a physics step, so every step is seen).
class LoggingQuadratureSource final : public EncoderSource {
 public:
  LoggingQuadratureSource(QuadratureStream& stream, SimTruthLog& log) : stream_(stream), log_(log) {}
  void fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out) override {
    stream_.fill_levels(first_cycle, out);
    const World& w = stream_.world();
    constexpr double kCyclesPerMs = static_cast<double>(BoardSim::kClockHz) / 1000.0;
    log_.add(static_cast<double>(w.cycle()) / kCyclesPerMs, w.truth(), w.gyro().report(w.gyro().raw_yaw_deg()));
  }

 private:
  QuadratureStream& stream_;
  SimTruthLog& log_;
};

/// Daemon time = the board's simulated time; waiting runs the board.
class BoardSimClock final : public daemon::DaemonClock {
 public:
  explicit BoardSimClock(BoardSim& board) : board_(board) {}
  double now_ms() override { return board_.seconds() * 1000.0; }
  void wait_ms(double ms) override {
    if (ms > 0) board_.run_cycles(static_cast<std::int64_t>(ms * (BoardSim::kClockHz / 1000)));
  }

 private:
  BoardSim& board_;
};

/// Everything of the simulated robot, wired: world -> encoders -> Verilated board -> transport.
struct VerilatedRobot {
  QuadratureStream stream;
  SimTruthLog log;
  LoggingQuadratureSource source;
  BoardSim board;
  BoardSimClock clock;

  VerilatedRobot(const WorldConfig& world, Trajectory trajectory)
      : stream(world, std::move(trajectory)), source(stream, log), board(&source), clock(board) {}

  /// A fresh SimTransport each time (the board itself keeps running, as after a USB replug).
  [[nodiscard]] daemon::TransportFactory transport_factory() {
    return [this]() -> std::unique_ptr<Transport> { return std::make_unique<SimTransport>(board); };
  }
};

}  // namespace omniloc::sim
