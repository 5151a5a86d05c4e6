// The UART side of the board's USB bridge: what the FT2232H's channel B is wired to. Served by the
// C++ reference board (reference_board.hpp) or, behind the same interface, the Verilated board top.
// Header-only so that host tests can use it without a library of their own.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <thread>

#include "omniloc/transport.hpp"

namespace omniloc::sim {

class UartSide {
 public:
  virtual ~UartSide() = default;
  /// Bytes the host sent, in order (bridge TX -> FPGA RX).
  virtual void to_board(std::span<const std::uint8_t> bytes) = 0;
  /// Moves up to out.size() bytes the board has sent (FPGA TX -> bridge RX) into out; returns the
  /// count.
  virtual std::size_t from_board(std::span<std::uint8_t> out) = 0;
};

/// A Transport straight onto a UartSide, with no USB in between: for protocol and client tests.
/// Single-threaded: the UART side answers synchronously, so when nothing is there, nothing will
/// come and read() just sleeps out its timeout.
class UartSideTransport final : public Transport {
 public:
  explicit UartSideTransport(UartSide& side) : side_(side) {}

  void write(std::span<const std::uint8_t> bytes) override {
    side_.to_board(bytes);
    counters_.bytes_written += bytes.size();
  }

  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override {
    const std::size_t n = side_.from_board(out);
    if (n == 0 && timeout.count() > 0) std::this_thread::sleep_for(std::min(timeout, max_sleep_));
    counters_.bytes_read += n;
    return n;
  }

  [[nodiscard]] TransportStatus status() const override {
    return TransportStatus{true, false, "in-process UART side", counters_};
  }

  /// Caps the sleep of an empty read, to keep tests fast.
  void set_max_sleep(std::chrono::milliseconds ms) { max_sleep_ = ms; }

 private:
  UartSide& side_;
  TransportCounters counters_;
  std::chrono::milliseconds max_sleep_{1};
};

}  // namespace omniloc::sim
