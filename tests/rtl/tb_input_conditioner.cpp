// input_conditioner testbench: random pin waveforms with runs shorter than, equal to and longer
// than the filter, for several filter lengths, against the segment-based golden filter.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <Vinput_conditioner.h>

#include "golden_encoder.hpp"
#include "tb_clocked.hpp"

namespace {

using omniloc::rtl_golden::Change;
using omniloc::rtl_tb::Clocked;
using omniloc::rtl_tb::TraceRequest;

struct Result {
  std::string failure;
  std::uint64_t fail_cycle = 0;
  std::uint64_t pin_changes = 0;
  std::uint64_t passed = 0;
};

Result run(unsigned len, bool initial, std::uint64_t seed, std::uint64_t cycles,
           const TraceRequest* trace) {
  std::mt19937_64 rng(seed);
  Result res;
  // Runs from 1 to 2*len+2 cycles: about half of them shorter than the filter.
  std::uniform_int_distribution<std::uint64_t> run_len(1, 2 * std::max(len, 1u) + 2);
  Clocked<Vinput_conditioner> dut(trace);
  dut->len_i = len;
  dut->in_i = initial;
  dut.reset(2);
  const std::uint64_t first = dut.cycle();
  std::vector<Change> pin;
  bool level = initial;
  for (std::uint64_t t = first + 2 + run_len(rng); t < first + cycles; t += run_len(rng)) {
    level = !level;
    pin.push_back({t, level});
  }
  res.pin_changes = pin.size();
  const auto golden = omniloc::rtl_golden::filter(initial, pin, len);
  res.passed = golden.size();
  std::size_t ip = 0;
  std::size_t ig = 0;
  bool expected = initial;
  bool in = initial;
  while (dut.cycle() < first + cycles + 2 * len + 8) {
    const std::uint64_t e = dut.cycle();
    if (ip < pin.size() && pin[ip].edge == e) in = pin[ip++].level;
    dut->in_i = in;
    dut.step();
    if (ig < golden.size() && golden[ig].edge == e) expected = golden[ig++].level;
    if (e >= first + 2) {
      if (!dut->valid_o) return res.failure = "valid_o low after priming", res.fail_cycle = e, res;
      if ((dut->out_o != 0) != expected) {
        res.failure = "out_o " + std::to_string(dut->out_o) + " at edge " + std::to_string(e) +
                      ", golden " + std::to_string(expected) + " (filter " + std::to_string(len) +
                      ")";
        res.fail_cycle = e;
        return res;
      }
    } else if (dut->valid_o) {
      return res.failure = "valid_o high before priming", res.fail_cycle = e, res;
    }
  }
  return res;
}

class InputConditioner : public ::testing::TestWithParam<unsigned> {};

TEST_P(InputConditioner, MatchesGoldenFilter) {
  const unsigned len = GetParam();
  const std::string name = "input_conditioner_len" + std::to_string(len);
  const std::uint64_t seed = omniloc::rtl_tb::test_seed(name, 1000 + len);
  for (const bool initial : {false, true}) {
    const auto res = run(len, initial, seed + initial, 400'000, nullptr);
    std::cout << "[" << name << "] initial=" << initial << " pin changes=" << res.pin_changes
              << " passed the filter=" << res.passed << "\n";
    if (!res.failure.empty()) {
      const TraceRequest tr{omniloc::rtl_tb::trace_path(name, seed + initial),
                            res.fail_cycle > 2000 ? res.fail_cycle - 2000 : 0};
      run(len, initial, seed + initial, res.fail_cycle + 10 - 2 * len - 8, &tr);
      FAIL() << res.failure << " seed " << seed + initial << "; trace: " << tr.path;
    }
    // Both sides of the filter length occurred.
    EXPECT_GT(res.passed, 0u);
    if (len > 1) {
      EXPECT_LT(res.passed, res.pin_changes);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(FilterLengths, InputConditioner,
                         ::testing::Values(0u, 1u, 2u, 3u, 7u, 64u, 255u));

}  // namespace
