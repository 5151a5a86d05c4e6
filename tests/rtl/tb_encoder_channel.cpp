// encoder_channel testbench: one channel from its pins to the captured window, with captures at
// irregular moments, against the golden filter + decoder + window models.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <Vencoder_channel.h>

#include <omniloc/regmap.hpp>

#include "golden_encoder.hpp"
#include "stream_gen.hpp"
#include "tb_clocked.hpp"

namespace {
namespace rm = omniloc::regmap;

using omniloc::rtl_golden::Mode;
using omniloc::rtl_tb::Clocked;
using omniloc::rtl_tb::TraceRequest;

struct Result {
  std::string failure;
  std::uint64_t fail_cycle = 0;
  std::uint64_t steps = 0;
  std::uint64_t windows = 0;
  std::uint64_t errors = 0;
};

Result run(std::uint64_t seed, unsigned filter_len, Mode mode, const TraceRequest* trace) {
  std::mt19937_64 rng(seed);
  Result res;
  // Irregular capture times (what the tick and ENABLE do in the core), 50..400 cycles apart.
  std::vector<std::uint64_t> ticks{200};
  omniloc::rtl_tb::StreamProfile p;
  p.min_gap = 1;
  p.max_gap = 8;
  p.p_reverse = 0.1;
  p.p_bounce = 0.1;
  p.p_illegal = 0.005;
  p.p_pause = 0.001;
  p.max_pause = 600;
  p.p_boundary_reversal = 0.02;
  while (ticks.size() < 20'000) ticks.push_back(ticks.back() + 50 + rng() % 351);
  const auto stream = omniloc::rtl_tb::generate_stream(rng, p, 200'000, 20, filter_len, ticks);
  res.steps = stream.steps;
  while (ticks.back() > stream.end_edge + 2000) ticks.pop_back();
  const auto pulses = omniloc::rtl_golden::channel_pulses(stream.a0, stream.b0, stream.a, stream.b,
                                                          filter_len, mode);
  const auto golden = omniloc::rtl_golden::windows(pulses, ticks);

  Clocked<Vencoder_channel> dut(trace);
  dut->a_i = stream.a0;
  dut->b_i = stream.b0;
  dut->filter_len_i = filter_len;
  dut->en_i = 1;
  dut->mode_i = static_cast<unsigned>(mode);
  dut->capture_i = 0;
  dut.reset(2);
  std::size_t ia = 0;
  std::size_t ib = 0;
  std::size_t k = 0;
  bool a = stream.a0;
  bool b = stream.b0;
  while (k < ticks.size()) {
    const std::uint64_t e = dut.cycle();
    if (ia < stream.a.size() && stream.a[ia].edge == e) a = stream.a[ia++].level;
    if (ib < stream.b.size() && stream.b[ib].edge == e) b = stream.b[ib++].level;
    dut->a_i = a;
    dut->b_i = b;
    // A tick visible after edge T captures at edge T + 1.
    dut->capture_i = (e == ticks[k] + 1);
    dut.step();
    if (e == ticks[k] + 1) {
      const auto& g = golden[k];
      res.errors += g.errors;
      // ERROR_COUNT saturates at 2^ERROR_COUNT_BITS - 1 (255).
      const std::uint64_t saturated =
          std::min<std::uint64_t>(res.errors, (1u << rm::kErrorCountBits) - 1);
      if (static_cast<std::int32_t>(dut->win_count_o) != g.count ||
          dut->win_position_o != g.position || (dut->win_dir_o != 0) != g.dir ||
          dut->err_count_o != saturated) {
        res.failure = "window " + std::to_string(k) + ": count " +
                      std::to_string(static_cast<std::int32_t>(dut->win_count_o)) + " position " +
                      std::to_string(dut->win_position_o) + " errors " +
                      std::to_string(dut->err_count_o) + "; golden " + std::to_string(g.count) +
                      " " + std::to_string(g.position) + " " + std::to_string(res.errors);
        res.fail_cycle = e;
        return res;
      }
      ++k;
      ++res.windows;
    }
  }
  return res;
}

TEST(EncoderChannel, MatchesGoldenWindowsInAllModes) {
  const std::uint64_t seed = omniloc::rtl_tb::test_seed("encoder_channel", 8080);
  for (const auto& [len, mode] : {std::pair{0u, Mode::kX4}, std::pair{2u, Mode::kX2},
                                  std::pair{5u, Mode::kX1}, std::pair{9u, Mode::kX4}}) {
    const auto res = run(seed + len, len, mode, nullptr);
    std::cout << "[encoder_channel] filter " << len << " mode " << static_cast<unsigned>(mode)
              << ": steps=" << res.steps << " windows=" << res.windows << " illegal=" << res.errors
              << "\n";
    if (!res.failure.empty()) {
      const TraceRequest tr{
          omniloc::rtl_tb::trace_path("encoder_channel_len" + std::to_string(len), seed + len),
          res.fail_cycle > 3000 ? res.fail_cycle - 3000 : 0};
      run(seed + len, len, mode, &tr);
      FAIL() << res.failure << " seed " << seed + len << "; trace: " << tr.path;
    }
    EXPECT_GT(res.errors, 0u);
  }
}

}  // namespace
