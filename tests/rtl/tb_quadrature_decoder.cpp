// quadrature_decoder testbench: random level sequences (legal steps both ways, holds, illegal
// double changes), random enable, valid and mode changes, every cycle against the table-based
// golden decoder.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <string>

#include <Vquadrature_decoder.h>

#include "golden_encoder.hpp"
#include "tb_clocked.hpp"

namespace {

using omniloc::rtl_golden::Decoder;
using omniloc::rtl_golden::Mode;
using omniloc::rtl_tb::Clocked;
using omniloc::rtl_tb::TraceRequest;

struct Result {
  std::string failure;
  std::uint64_t fail_cycle = 0;
  std::array<std::uint64_t, 3> counts{};  // up, down, err
};

Result run(std::uint64_t seed, std::uint64_t cycles, const TraceRequest* trace) {
  std::mt19937_64 rng(seed);
  Result res;
  Clocked<Vquadrature_decoder> dut(trace);
  Decoder golden;
  bool a = rng() & 1;
  bool b = rng() & 1;
  dut->a_i = a;
  dut->b_i = b;
  dut->valid_i = 0;
  dut->en_i = 1;
  dut->mode_i = 0;
  dut.reset(2);
  bool en = true;
  Mode mode = Mode::kX4;
  for (std::uint64_t i = 0; i < cycles; ++i) {
    const unsigned r = static_cast<unsigned>(rng() % 1000);
    if (r < 300) {
      a = !a;  // one pin: a legal step in some direction
    } else if (r < 600) {
      b = !b;
    } else if (r < 610) {
      a = !a;  // both: illegal
      b = !b;
    }
    if (rng() % 500 == 0) en = !en;
    if (rng() % 300 == 0) mode = static_cast<Mode>(rng() % 3);
    const bool valid = i >= 5;
    dut->a_i = a;
    dut->b_i = b;
    dut->valid_i = valid;
    dut->en_i = en;
    dut->mode_i = static_cast<unsigned>(mode);
    const std::uint64_t e = dut.cycle();
    dut.step();
    const auto g = golden.sample(a, b, valid, en, mode);
    if ((dut->up_o != 0) != g.up || (dut->down_o != 0) != g.down || (dut->err_o != 0) != g.err ||
        (dut->dir_o != 0) != g.dir) {
      res.failure = "edge " + std::to_string(e) + ": up/down/err/dir " + std::to_string(dut->up_o) +
                    std::to_string(dut->down_o) + std::to_string(dut->err_o) +
                    std::to_string(dut->dir_o) + ", golden " + std::to_string(g.up) +
                    std::to_string(g.down) + std::to_string(g.err) + std::to_string(g.dir) +
                    " (mode " + std::to_string(static_cast<unsigned>(mode)) + ", en " +
                    std::to_string(en) + ")";
      res.fail_cycle = e;
      return res;
    }
    res.counts[0] += g.up;
    res.counts[1] += g.down;
    res.counts[2] += g.err;
  }
  return res;
}

TEST(QuadratureDecoder, MatchesGoldenTableInAllModes) {
  const std::uint64_t seed = omniloc::rtl_tb::test_seed("quadrature_decoder", 77);
  const auto res = run(seed, 2'000'000, nullptr);
  std::cout << "[quadrature_decoder] up=" << res.counts[0] << " down=" << res.counts[1]
            << " illegal=" << res.counts[2] << "\n";
  if (!res.failure.empty()) {
    const TraceRequest tr{omniloc::rtl_tb::trace_path("quadrature_decoder", seed),
                          res.fail_cycle > 2000 ? res.fail_cycle - 2000 : 0};
    run(seed, res.fail_cycle + 2, &tr);
    FAIL() << res.failure << " seed " << seed << "; trace: " << tr.path;
  }
  EXPECT_GT(res.counts[0], 100'000u);
  EXPECT_GT(res.counts[1], 100'000u);
  EXPECT_GT(res.counts[2], 1'000u);
}

// Hand-computed: one forward cycle 00 -> 10 -> 11 -> 01 -> 00 counts 4 in X4, 2 in X2, 1 in X1,
// and the same cycle backwards gives the negatives.
TEST(QuadratureDecoder, OneCycleHandComputed) {
  const std::array<std::array<int, 2>, 5> forward = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}}};
  for (const auto& [mode, expected] :
       std::array<std::pair<unsigned, int>, 3>{{{0, 4}, {1, 2}, {2, 1}}}) {
    for (const bool backwards : {false, true}) {
      Clocked<Vquadrature_decoder> dut;
      dut->a_i = 0;
      dut->b_i = 0;
      dut->valid_i = 1;
      dut->en_i = 1;
      dut->mode_i = mode;
      dut.reset(2);
      dut.step();
      dut.step();
      int count = 0;
      for (int i = 1; i < 5; ++i) {
        const auto& ab = forward[backwards ? 4 - i : i];
        dut->a_i = ab[0];
        dut->b_i = ab[1];
        dut.step();
        count += dut->up_o - dut->down_o;
        EXPECT_EQ(dut->err_o, 0);
      }
      EXPECT_EQ(count, backwards ? -expected : expected) << "mode " << mode;
      EXPECT_EQ(dut->dir_o, backwards ? 1 : 0);
    }
  }
}

}  // namespace
