#include "omniloc_sim/board_sim.hpp"

#include <verilated.h>
#include <verilated_vcd_c.h>

#include <array>
#include <deque>
#include <string>
#include <vector>

#include "Vomniloc_top.h"
// The model's root (generated, with anonymous structs): for the clock's previous value,
// step_clock().
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpedantic"
#include "Vomniloc_top___024root.h"
#pragma GCC diagnostic pop

namespace omniloc::sim {

namespace {

constexpr std::int64_t kCyclesPerBit = BoardSim::kClockHz / BoardSim::kBaud;
static_assert(BoardSim::kClockHz % BoardSim::kBaud == 0,
              "the simulated line rate must divide the clock");
constexpr std::size_t kLevelBlock = 4096;

// Split an EncoderSource levels byte into the A and B pin masks of the core.
constexpr std::array<std::uint16_t, 256> make_pin_table() {
  std::array<std::uint16_t, 256> t{};
  for (unsigned v = 0; v < 256; ++v) {
    unsigned a = 0, b = 0;
    for (unsigned m = 0; m < 4; ++m) {
      a |= ((v >> (2 * m)) & 1u) << m;
      b |= ((v >> (2 * m + 1)) & 1u) << m;
    }
    t[v] = static_cast<std::uint16_t>(a | b << 4);
  }
  return t;
}
constexpr auto kPinTable = make_pin_table();

// Makes the model take the clock as low, as an eval() of the falling edge would, when this
// Verilator keeps the clock's previous value where we know it (5.006); false otherwise.
template <typename Root>
bool forget_clock_high(Root& root) {
  if constexpr (requires { root.__Vtrigrprev__TOP__clk_i = 0; }) {
    root.__Vtrigrprev__TOP__clk_i = 0;
    return true;
  } else {
    return false;
  }
}

}  // namespace

struct BoardSim::Impl {
  std::unique_ptr<VerilatedContext> context = std::make_unique<VerilatedContext>();
  std::unique_ptr<Vomniloc_top> top;
  std::unique_ptr<VerilatedVcdC> trace;
  EncoderSource* source = nullptr;
  Icm42688* gyro = nullptr;
  std::int64_t cycle = 0;  // since the end of reset
  std::uint64_t trace_time = 0;

  std::vector<std::uint8_t> levels = std::vector<std::uint8_t>(kLevelBlock, 0);
  std::size_t level_index = kLevelBlock;

  // Host -> FPGA serializer (the FT2232H's TX): 10 bits a byte, back to back.
  std::deque<std::uint8_t> to_board;
  std::uint16_t tx_frame = 0;  // bits still to send, LSB first
  int tx_bits_left = 0;
  std::int64_t tx_bit_cycles_left = 0;

  // FPGA -> host decoder (the FT2232H's RX).
  std::deque<std::uint8_t> from_board;
  bool rx_prev = true;
  bool rx_active = false;
  std::int64_t rx_sample_in = 0;
  int rx_bit = 0;  // 0 start, 1..8 data, 9 stop
  std::uint8_t rx_byte = 0;

  BoardSimCounters counters;

  bool rx_line_level() {
    if (tx_bit_cycles_left == 0) {
      if (tx_bits_left == 0 && !to_board.empty()) {
        tx_frame =
            static_cast<std::uint16_t>((to_board.front() << 1) | 0x200u);  // start 0, data, stop 1
        to_board.pop_front();
        tx_bits_left = 10;
      }
      if (tx_bits_left > 0) {
        tx_bit_cycles_left = kCyclesPerBit;
      }
    }
    if (tx_bits_left == 0) return true;  // idle
    const bool level = (tx_frame & 1u) != 0;
    if (--tx_bit_cycles_left == 0) {
      tx_frame >>= 1;
      --tx_bits_left;
    }
    return level;
  }

  void decode_tx_line(bool level) {
    if (!rx_active) {
      if (rx_prev && !level) {  // start bit edge: sample in the middle of each bit
        rx_active = true;
        rx_bit = 0;
        rx_byte = 0;
        rx_sample_in = kCyclesPerBit / 2;
      }
    } else if (--rx_sample_in == 0) {
      if (rx_bit == 0) {
        if (level) rx_active = false;  // not a start bit after all
      } else if (rx_bit <= 8) {
        rx_byte = static_cast<std::uint8_t>(rx_byte | (level ? 1u : 0u) << (rx_bit - 1));
      } else {
        if (level) {
          from_board.push_back(rx_byte);
          ++counters.bytes_from_board;
        } else {
          ++counters.tx_framing_errors;
        }
        rx_active = false;
      }
      ++rx_bit;
      rx_sample_in = kCyclesPerBit;
    }
    rx_prev = level;
  }

  // One clock cycle. The design has only posedge clk_i logic, so the falling edge changes no state
  // and no output: without a trace it is not evaluated (a whole eval() of the model, ~10 % of a
  // cycle); the next eval() still has to see the clock fall before it rises, which Verilator 5.006
  // keeps as the clock's previous value (the root's __Vtrigrprev__TOP__clk_i). A Verilator that
  // names it otherwise evaluates the falling edge as before. With a trace both edges are dumped.
  void step_clock() {
    top->clk_i = 1;
    top->eval();
    if (trace) trace->dump(trace_time++);
    top->clk_i = 0;
    if (!trace && forget_clock_high(*top->rootp)) return;
    top->eval();
    if (trace) trace->dump(trace_time++);
  }
};

BoardSim::BoardSim(EncoderSource* source, Icm42688* gyro) : impl_(std::make_unique<Impl>()) {
  impl_->context->traceEverOn(true);
  impl_->top = std::make_unique<Vomniloc_top>(impl_->context.get());
  impl_->source = source;
  impl_->gyro = gyro;
  auto& top = *impl_->top;
  top.uart_rx_i = 1;
  top.spi_miso_i = 1;
  top.enc_a_i = 0;
  top.enc_b_i = 0;
  top.rst_i = 1;
  for (int i = 0; i < 4; ++i) impl_->step_clock();
  top.rst_i = 0;
}

BoardSim::~BoardSim() {
  if (impl_->trace) impl_->trace->close();
  impl_->top->final();
}

void BoardSim::to_board(std::span<const std::uint8_t> bytes) {
  impl_->to_board.insert(impl_->to_board.end(), bytes.begin(), bytes.end());
  impl_->counters.bytes_to_board += bytes.size();
}

std::size_t BoardSim::from_board(std::span<std::uint8_t> out) {
  std::size_t n = 0;
  while (n < out.size() && !impl_->from_board.empty()) {
    out[n++] = impl_->from_board.front();
    impl_->from_board.pop_front();
  }
  return n;
}

void BoardSim::run_cycles(std::int64_t cycles) {
  auto& s = *impl_;
  auto& top = *s.top;
  for (std::int64_t i = 0; i < cycles; ++i) {
    if (s.source) {
      if (s.level_index == kLevelBlock) {
        s.source->fill_levels(s.cycle, s.levels);
        s.level_index = 0;
      }
      const std::uint16_t pins = kPinTable[s.levels[s.level_index++]];
      top.enc_a_i = pins & 0xF;
      top.enc_b_i = (pins >> 4) & 0xF;
    }
    top.uart_rx_i = s.rx_line_level() ? 1 : 0;
    s.step_clock();
    s.decode_tx_line(top.uart_tx_o != 0);
    // The gyro sees the pins this edge left and answers MISO for the next one.
    if (s.gyro)
      top.spi_miso_i =
          s.gyro->step(top.spi_cs_n_o != 0, top.spi_sclk_o != 0, top.spi_mosi_o != 0) ? 1 : 0;
    ++s.cycle;
  }
}

std::int64_t BoardSim::cycle() const {
  return impl_->cycle;
}
std::size_t BoardSim::pending_from_board() const {
  return impl_->from_board.size();
}
BoardSimCounters BoardSim::counters() const {
  return impl_->counters;
}
bool BoardSim::activity_led() const {
  return impl_->top->activity_o != 0;
}
bool BoardSim::error_led() const {
  return impl_->top->error_o != 0;
}

void BoardSim::open_trace(const std::string& vcd_path) {
  impl_->trace = std::make_unique<VerilatedVcdC>();
  impl_->top->trace(impl_->trace.get(), 99);
  impl_->trace->open(vcd_path.c_str());
}

void SimTransport::write(std::span<const std::uint8_t> bytes) {
  board_.to_board(bytes);
  counters_.bytes_written += bytes.size();
}

std::size_t SimTransport::read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) {
  // Run in slices of 100 us of board time until something arrives or the timeout has passed.
  constexpr std::int64_t kSlice = BoardSim::kClockHz / 10'000;
  const std::int64_t deadline = board_.cycle() + timeout.count() * (BoardSim::kClockHz / 1000);
  std::size_t n = board_.from_board(out);
  while (n == 0 && board_.cycle() < deadline) {
    board_.run_cycles(kSlice);
    n = board_.from_board(out);
  }
  counters_.bytes_read += n;
  return n;
}

TransportStatus SimTransport::status() const {
  static const std::string description = "Verilated omniloc_top (" +
                                         std::to_string(BoardSim::kClockHz / 1'000'000) + " MHz, " +
                                         std::to_string(BoardSim::kBaud) + " baud) in-process";
  return TransportStatus{true, false, description, counters_};
}

}  // namespace omniloc::sim
