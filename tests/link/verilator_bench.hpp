// A clocked bench around one Verilated model: steps the clock and, on request, writes a VCD trace.
// The link testbenches run each scenario with a seed; a failing scenario is run again with the
// same seed and a trace, whose path the test prints.
#pragma once

#include <verilated.h>
#include <verilated_vcd_c.h>

#include <cstdint>
#include <memory>
#include <string>

#include "tb_util.hpp"

namespace omniloc::tb {

template <class Model>
class VerilatorBench {
 public:
  explicit VerilatorBench(const std::string& vcd_path = {})
      : context_(std::make_unique<VerilatedContext>()) {
    if (!vcd_path.empty()) context_->traceEverOn(true);
    model_ = std::make_unique<Model>(context_.get());
    if (!vcd_path.empty()) {
      trace_ = std::make_unique<VerilatedVcdC>();
      model_->trace(trace_.get(), 99);
      trace_->open(vcd_path.c_str());
    }
    model_->clk_i = 0;
    model_->rst_i = 1;
    model_->eval();
  }
  VerilatorBench(const VerilatorBench&) = delete;
  VerilatorBench& operator=(const VerilatorBench&) = delete;
  ~VerilatorBench() {
    if (trace_) trace_->close();
    model_->final();
  }

  Model& dut() { return *model_; }
  [[nodiscard]] std::uint64_t cycle() const { return cycle_; }

  /// One rising edge. Inputs set before the call are sampled at this edge; outputs read after it
  /// are the registered values after the edge.
  void step() {
    model_->clk_i = 1;
    model_->eval();
    if (trace_) trace_->dump(2 * cycle_ + 1);
    model_->clk_i = 0;
    model_->eval();
    if (trace_) trace_->dump(2 * cycle_ + 2);
    ++cycle_;
  }

  void reset(int cycles = 4) {
    model_->rst_i = 1;
    for (int i = 0; i < cycles; ++i) step();
    model_->rst_i = 0;
  }

 private:
  std::unique_ptr<VerilatedContext> context_;
  std::unique_ptr<Model> model_;
  std::unique_ptr<VerilatedVcdC> trace_;
  std::uint64_t cycle_ = 0;
};

}  // namespace omniloc::tb
