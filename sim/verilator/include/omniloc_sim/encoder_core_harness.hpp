// Cycle-level harness around the Verilated rtl/encoder_core.v (library vencoder_core).
//
// One clock cycle per step(): the inputs set before step() are what the core samples at that
// rising edge, and the outputs read after step() are the registered values after it. The register
// bus is driven for exactly one cycle per request (the step() that samples it). The bus is
// pipelined (docs/RTL.md): the request takes effect at the next edge and its answer (reg_ack_o)
// is visible after kBusLatency steps; requests may be issued back to back, answers come in order.
// read()/write() issue one request and step until its answer (the encoder pins keep their levels).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

class Vencoder_core;
class VerilatedContext;
class VerilatedVcdC;

namespace omniloc_sim {

/// The answer of the register bus to one request.
struct BusResult {
  std::uint32_t data = 0;
  bool err = false;
};

/// The window bank as the core shows it on its streaming outputs.
struct CoreWindow {
  std::uint32_t seq = 0;
  std::uint32_t timestamp = 0;
  std::array<std::int32_t, 4> count{};
  std::array<std::uint32_t, 4> position{};
  std::uint8_t dir = 0;
  std::uint8_t status = 0;
};

class EncoderCoreHarness {
 public:
  /// Builds the model and holds reset for `reset_cycles` cycles.
  explicit EncoderCoreHarness(int reset_cycles = 2);
  ~EncoderCoreHarness();
  EncoderCoreHarness(const EncoderCoreHarness&) = delete;
  EncoderCoreHarness& operator=(const EncoderCoreHarness&) = delete;

  /// Synchronous reset for `cycles` cycles (the pins keep their levels).
  void reset(int cycles = 2);
  /// One rising clock edge.
  void step();
  void step(std::uint64_t cycles);

  /// Encoder pin levels, bit n = channel n.
  void set_pins(std::uint8_t a_mask, std::uint8_t b_mask);
  void set_channel(int channel, bool a, bool b);

  /// Steps from issuing a request until its answer is in response().
  static constexpr int kBusLatency = 3;
  /// Present a request during the next step() only; its answer is in response() kBusLatency steps
  /// later.
  void issue_read(std::uint8_t addr);
  void issue_write(std::uint8_t addr, std::uint32_t data);
  /// The bus answer acknowledged at the last step, if any.
  std::optional<BusResult> response() const;
  /// Blocking access: kBusLatency cycles.
  BusResult read(std::uint8_t addr);
  BusResult write(std::uint8_t addr, std::uint32_t data);

  /// Strobe win_consumed_i during the next step().
  void consume_window();

  bool win_valid() const;
  bool tick() const;
  bool stream_enabled() const;
  CoreWindow window() const;

  /// Cycles stepped since construction (reset cycles included).
  std::uint64_t cycle() const { return cycle_; }

  /// Dump every following cycle into a VCD file until close_trace() or destruction.
  void open_trace(const std::string& vcd_path);
  void close_trace();

  /// Direct access to the Verilated model's ports, for what the helpers above do not cover.
  Vencoder_core& model() { return *top_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vencoder_core> top_;
  std::unique_ptr<VerilatedVcdC> trace_;
  std::uint64_t cycle_ = 0;
  std::uint64_t time_ps_ = 0;
  bool clear_bus_after_step_ = false;
};

}  // namespace omniloc_sim
