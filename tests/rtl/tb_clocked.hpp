// A minimal clocked wrapper around a Verilated module, shared by the RTL testbenches.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <verilated.h>
#include <verilated_vcd_c.h>

#include "tb_support.hpp"

namespace omniloc::rtl_tb {

/// A Verilated module with clk_i/rst_i: one rising edge per step(). Inputs set before step()
/// are sampled at that edge; outputs read after it are the values after the edge.
template <class Model>
class Clocked {
 public:
  explicit Clocked(const TraceRequest* trace = nullptr)
      : ctx_(std::make_unique<VerilatedContext>()) {
    ctx_->traceEverOn(true);
    top_ = std::make_unique<Model>(ctx_.get(), "top");
    if (trace != nullptr) trace_request_ = *trace;
    top_->clk_i = 0;
    top_->rst_i = 1;
    top_->eval();
  }
  ~Clocked() {
    if (vcd_) vcd_->close();
    top_->final();
  }
  Clocked(const Clocked&) = delete;
  Clocked& operator=(const Clocked&) = delete;

  Model* operator->() { return top_.get(); }
  Model& io() { return *top_; }
  std::uint64_t cycle() const { return cycle_; }

  void step() {
    if (!trace_request_.path.empty() && !vcd_ && cycle_ >= trace_request_.from_cycle) {
      vcd_ = std::make_unique<VerilatedVcdC>();
      top_->trace(vcd_.get(), 99);
      vcd_->open(trace_request_.path.c_str());
    }
    top_->clk_i = 0;
    top_->eval();
    if (vcd_) vcd_->dump(2 * cycle_);
    top_->clk_i = 1;
    top_->eval();
    if (vcd_) vcd_->dump(2 * cycle_ + 1);
    ++cycle_;
  }

  void reset(int cycles = 2) {
    top_->rst_i = 1;
    for (int i = 0; i < cycles; ++i) step();
    top_->rst_i = 0;
  }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Model> top_;
  std::unique_ptr<VerilatedVcdC> vcd_;
  TraceRequest trace_request_;
  std::uint64_t cycle_ = 0;
};

}  // namespace omniloc::rtl_tb
