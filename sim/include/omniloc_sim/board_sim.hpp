// The simulated encoder board: the Verilated rtl/omniloc_top.v (encoder core + UART link, as on the
// iCEBreaker at its board clock and UART rate, regmap::kBoardClockHz and regmap::kUartBaud: 12 MHz
// and 1 Mbaud) with models of what its pins are wired to: the FT2232H's UART side (a bit-exact
// serializer into the FPGA's RX pin and a decoder of its TX pin), the four encoders (an
// EncoderSource that gives the A/B levels of every clock cycle) and the ICM-42688-P gyro on the SPI
// pins (sim::Icm42688, stepped every cycle; without one MISO reads 1, the pull-up of an empty
// PMOD).
//
// BoardSim is a UartSide, so it plugs into the FT2232H model under umockdev; SimTransport puts it
// behind the host's Transport interface in-process, advancing simulated time while the host waits.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "omniloc/regmap.hpp"
#include "omniloc/transport.hpp"
#include "omniloc_sim/encoder_waveform.hpp"
#include "omniloc_sim/icm42688.hpp"
#include "omniloc_sim/uart_side.hpp"

namespace omniloc::sim {

/// The encoder pin levels, cycle by cycle: bit 2m is A and bit 2m+1 is B of motor m.
class EncoderSource {
 public:
  virtual ~EncoderSource() = default;
  /// Levels for cycles first_cycle, first_cycle + 1, ...; calls move forward in time.
  virtual void fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out) = 0;
};

/// Encoders driven by the world simulator's quadrature stream (sim/world). The stream's cycle 0 is
/// the board's first cycle after reset.
class QuadratureSource final : public EncoderSource {
 public:
  explicit QuadratureSource(QuadratureStream& stream) : stream_(stream) {}
  void fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out) override {
    stream_.fill_levels(first_cycle, out);
  }

 private:
  QuadratureStream& stream_;
};

struct BoardSimCounters {
  std::uint64_t bytes_to_board = 0;
  std::uint64_t bytes_from_board = 0;
  std::uint64_t tx_framing_errors = 0;  ///< FPGA TX bytes with a low stop bit (never expected)
};

class BoardSim final : public UartSide {
 public:
  // omniloc_top's defaults, as on the iCEBreaker (common/regmap.json "link").
  static constexpr std::int64_t kClockHz = regmap::kBoardClockHz;
  static constexpr std::int64_t kBaud = regmap::kUartBaud;

  /// Builds the model and holds reset for 4 cycles; `source` may be null (all pins low), `gyro`
  /// null (no gyro fitted: MISO high). Both must outlive the board; the gyro is stepped at the
  /// board's clock (its Icm42688Params::clk_hz must be kClockHz).
  explicit BoardSim(EncoderSource* source = nullptr, Icm42688* gyro = nullptr);
  ~BoardSim() override;
  BoardSim(const BoardSim&) = delete;
  BoardSim& operator=(const BoardSim&) = delete;

  // UartSide
  void to_board(std::span<const std::uint8_t> bytes) override;
  std::size_t from_board(std::span<std::uint8_t> out) override;

  /// Advances the board by `cycles` clock cycles.
  void run_cycles(std::int64_t cycles);
  /// Cycles since the end of reset: the encoder source's time base.
  [[nodiscard]] std::int64_t cycle() const;
  [[nodiscard]] double seconds() const { return static_cast<double>(cycle()) / kClockHz; }
  [[nodiscard]] std::size_t pending_from_board() const;
  [[nodiscard]] BoardSimCounters counters() const;
  /// The board's LEDs.
  [[nodiscard]] bool activity_led() const;
  [[nodiscard]] bool error_led() const;

  /// Writes every following cycle into a VCD file (slows the simulation ~10x).
  void open_trace(const std::string& vcd_path);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A board's simulated time as a steady_clock time point (for Transport::now()).
[[nodiscard]] inline std::chrono::steady_clock::time_point board_time(const BoardSim& board) {
  const std::int64_t c = board.cycle();
  const std::int64_t ns = (c / BoardSim::kClockHz) * 1'000'000'000 +
                          (c % BoardSim::kClockHz) * 1'000'000'000 / BoardSim::kClockHz;
  return std::chrono::steady_clock::time_point(
      std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::nanoseconds(ns)));
}

/// The host's Transport straight onto a BoardSim: write() queues bytes for the board's RX pin;
/// read() runs the board until bytes arrive or `timeout` of simulated time has passed.
class SimTransport final : public Transport {
 public:
  explicit SimTransport(BoardSim& board) : board_(board) {}
  void write(std::span<const std::uint8_t> bytes) override;
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override;
  [[nodiscard]] TransportStatus status() const override;
  /// Board time: timeouts and the host's deadlines run on the simulated clock.
  [[nodiscard]] std::chrono::steady_clock::time_point now() const override {
    return board_time(board_);
  }

 private:
  BoardSim& board_;
  TransportCounters counters_;
};

}  // namespace omniloc::sim
