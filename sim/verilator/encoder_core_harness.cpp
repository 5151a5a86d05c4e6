#include "omniloc_sim/encoder_core_harness.hpp"

#include <stdexcept>

#include <Vencoder_core.h>
#include <verilated.h>
#include <verilated_vcd_c.h>

namespace omniloc_sim {
namespace {
// 40 MHz: 25 ns per cycle, only for the time axis of traces.
constexpr std::uint64_t kHalfPeriodPs = 12500;
}  // namespace

EncoderCoreHarness::EncoderCoreHarness(int reset_cycles)
    : ctx_(std::make_unique<VerilatedContext>()) {
  // Must precede the model's construction for trace code to be active later.
  ctx_->traceEverOn(true);
  top_ = std::make_unique<Vencoder_core>(ctx_.get(), "encoder_core");
  top_->clk_i = 0;
  top_->enc_a_i = 0;
  top_->enc_b_i = 0;
  top_->reg_rd_i = 0;
  top_->reg_wr_i = 0;
  top_->win_consumed_i = 0;
  top_->eval();
  reset(reset_cycles);
}

EncoderCoreHarness::~EncoderCoreHarness() {
  close_trace();
  top_->final();
}

void EncoderCoreHarness::reset(int cycles) {
  if (cycles < 1) throw std::invalid_argument("EncoderCoreHarness::reset: cycles must be >= 1");
  top_->rst_i = 1;
  step(static_cast<std::uint64_t>(cycles));
  top_->rst_i = 0;
}

void EncoderCoreHarness::step() {
  top_->clk_i = 0;
  top_->eval();
  if (trace_) trace_->dump(time_ps_);
  time_ps_ += kHalfPeriodPs;
  top_->clk_i = 1;
  top_->eval();
  if (trace_) trace_->dump(time_ps_);
  time_ps_ += kHalfPeriodPs;
  ++cycle_;
  // Requests and strobes last exactly one cycle.
  top_->reg_rd_i = 0;
  top_->reg_wr_i = 0;
  top_->win_consumed_i = 0;
}

void EncoderCoreHarness::step(std::uint64_t cycles) {
  for (std::uint64_t i = 0; i < cycles; ++i) step();
}

void EncoderCoreHarness::set_pins(std::uint8_t a_mask, std::uint8_t b_mask) {
  top_->enc_a_i = a_mask & 0xF;
  top_->enc_b_i = b_mask & 0xF;
}

void EncoderCoreHarness::set_channel(int channel, bool a, bool b) {
  if (channel < 0 || channel > 3) {
    throw std::out_of_range("EncoderCoreHarness::set_channel: channel " + std::to_string(channel) +
                            " is not in 0..3");
  }
  const auto bit = static_cast<std::uint8_t>(1u << channel);
  top_->enc_a_i = static_cast<std::uint8_t>(a ? (top_->enc_a_i | bit) : (top_->enc_a_i & ~bit));
  top_->enc_b_i = static_cast<std::uint8_t>(b ? (top_->enc_b_i | bit) : (top_->enc_b_i & ~bit));
}

void EncoderCoreHarness::issue_read(std::uint8_t addr) {
  top_->reg_addr_i = addr;
  top_->reg_rd_i = 1;
  top_->reg_wr_i = 0;
}

void EncoderCoreHarness::issue_write(std::uint8_t addr, std::uint32_t data) {
  top_->reg_addr_i = addr;
  top_->reg_wdata_i = data;
  top_->reg_wr_i = 1;
  top_->reg_rd_i = 0;
}

std::optional<BusResult> EncoderCoreHarness::response() const {
  if (!top_->reg_ack_o) return std::nullopt;
  return BusResult{top_->reg_rdata_o, top_->reg_err_o != 0};
}

BusResult EncoderCoreHarness::read(std::uint8_t addr) {
  issue_read(addr);
  for (int i = 0; i < kBusLatency; ++i) {
    if (i > 0 && response()) {
      throw std::logic_error("encoder_core: reg_ack_o too early after a read of address " +
                             std::to_string(addr));
    }
    step();
  }
  const auto r = response();
  if (!r)
    throw std::logic_error("encoder_core: no reg_ack_o " + std::to_string(kBusLatency) +
                           " cycles after a read of address " + std::to_string(addr));
  return *r;
}

BusResult EncoderCoreHarness::write(std::uint8_t addr, std::uint32_t data) {
  issue_write(addr, data);
  for (int i = 0; i < kBusLatency; ++i) {
    if (i > 0 && response()) {
      throw std::logic_error("encoder_core: reg_ack_o too early after a write of address " +
                             std::to_string(addr));
    }
    step();
  }
  const auto r = response();
  if (!r)
    throw std::logic_error("encoder_core: no reg_ack_o " + std::to_string(kBusLatency) +
                           " cycles after a write of address " + std::to_string(addr));
  return *r;
}

void EncoderCoreHarness::consume_window() {
  top_->win_consumed_i = 1;
}

bool EncoderCoreHarness::win_valid() const {
  return top_->win_valid_o != 0;
}
bool EncoderCoreHarness::tick() const {
  return top_->tick_o != 0;
}
bool EncoderCoreHarness::stream_enabled() const {
  return top_->stream_en_o != 0;
}

CoreWindow EncoderCoreHarness::window() const {
  CoreWindow w;
  w.seq = top_->win_seq_o;
  w.timestamp = top_->win_timestamp_o;
  for (int ch = 0; ch < 4; ++ch) {
    w.count[ch] = static_cast<std::int32_t>(top_->win_count_o[ch]);
    w.position[ch] = top_->win_position_o[ch];
  }
  w.dir = top_->win_dir_o;
  w.status = top_->status_o;
  return w;
}

void EncoderCoreHarness::open_trace(const std::string& vcd_path) {
  close_trace();
  trace_ = std::make_unique<VerilatedVcdC>();
  top_->trace(trace_.get(), 99);
  trace_->open(vcd_path.c_str());
  if (!trace_->isOpen()) {
    trace_.reset();
    throw std::runtime_error("EncoderCoreHarness: cannot open trace file '" + vcd_path + "'");
  }
}

void EncoderCoreHarness::close_trace() {
  if (trace_) {
    trace_->close();
    trace_.reset();
  }
}

}  // namespace omniloc_sim
