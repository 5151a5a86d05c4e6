// uart_rx against a golden serial line generator with per-byte baud errors of up to +-2 %, random
// gaps, injected framing errors and glitches, and a consumer that stalls (overruns).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "Vuart_rx.h"
#include "omniloc/regmap.hpp"
#include "tb_clocked.hpp"

namespace {

// The module's defaults are the board's clock and baud (common/regmap.json "link"): 12 cycles a
// bit.
constexpr double kClksPerBit =
    static_cast<double>(omniloc::regmap::kBoardClockHz) / omniloc::regmap::kUartBaud;

struct LineEvent {
  std::uint64_t cycle;
  std::uint8_t level;
};

struct Stimulus {
  std::vector<std::uint8_t> levels;      // the line, one sample a clock cycle
  std::vector<std::uint8_t> good_bytes;  // bytes sent with a correct stop bit
  int framing_errors = 0;
};

// Builds a line: each byte at its own bit rate (error up to +-2 %), some with a low stop bit,
// separated by idle gaps, some gaps holding a glitch shorter than a third of a bit.
Stimulus make_line(std::uint64_t seed, int count, double framing_probability) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> rate_error(-0.02, 0.02);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Stimulus s;
  auto hold = [&](std::uint8_t level, double cycles, double& t) {
    const double end = t + cycles;
    while (static_cast<double>(s.levels.size()) < std::round(end)) s.levels.push_back(level);
    t = end;
  };
  double t = 0.0;
  hold(1, 30, t);
  for (int i = 0; i < count; ++i) {
    const auto byte = static_cast<std::uint8_t>(rng());
    const double bit = kClksPerBit * (1.0 + rate_error(rng));
    const bool bad_stop = unit(rng) < framing_probability;
    hold(0, bit, t);
    for (int b = 0; b < 8; ++b) hold(static_cast<std::uint8_t>((byte >> b) & 1u), bit, t);
    hold(bad_stop ? 0 : 1, bit, t);
    if (bad_stop) {
      ++s.framing_errors;
    } else {
      s.good_bytes.push_back(byte);
    }
    hold(1, 2 + static_cast<double>(rng() % 30), t);
    if (rng() % 8 == 0) {  // a glitch on the idle line: too short to be a start bit
      hold(0, 1 + static_cast<double>(rng() % 3), t);
      hold(1, 2 * kClksPerBit, t);
    }
  }
  hold(1, 40, t);
  return s;
}

struct Result {
  std::vector<std::uint8_t> bytes;
  int framing = 0;
  int overruns = 0;
};

// Plays the line into the receiver; the consumer takes a byte when `ready(cycle)` says so.
template <class Ready>
Result play(const Stimulus& s, Ready ready, const std::string& vcd = {}) {
  const omniloc::rtl_tb::TraceRequest trace{vcd, 0};
  omniloc::rtl_tb::Clocked<Vuart_rx> bench(vcd.empty() ? nullptr : &trace);
  auto& dut = bench.io();
  dut.rx_i = 1;
  bench.reset();
  Result r;
  for (std::size_t c = 0; c < s.levels.size() + 200; ++c) {
    dut.rx_i = c < s.levels.size() ? s.levels[c] : 1;
    dut.ready_i = ready(c) ? 1 : 0;
    if (dut.valid_o && dut.ready_i) r.bytes.push_back(dut.data_o);
    bench.step();
  }
  // Drain what is left.
  dut.ready_i = 1;
  if (dut.valid_o) r.bytes.push_back(dut.data_o);
  r.framing = dut.framing_errors_o;
  r.overruns = dut.overruns_o;
  return r;
}

TEST(UartRx, BytesAtBaudErrorsWithFramingErrorsAndGlitches) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 21);
  const auto s = make_line(seed, 4000, 0.05);
  const auto always = [](std::size_t) { return true; };
  const auto r = play(s, always);
  if (r.bytes != s.good_bytes || r.framing != s.framing_errors || r.overruns != 0) {
    const auto vcd = omniloc::rtl_tb::trace_path("uart_rx", seed);
    play(s, always, vcd);
    ADD_FAILURE() << "trace: " << vcd;
  }
  EXPECT_EQ(r.bytes.size(), s.good_bytes.size());
  EXPECT_EQ(r.bytes, s.good_bytes);
  EXPECT_EQ(r.framing, s.framing_errors);
  EXPECT_EQ(r.overruns, 0);
}

TEST(UartRx, StalledConsumerKeepsOldestByteAndCountsEveryOverrun) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 22);
  const auto s = make_line(seed, 50, 0.0);
  // The consumer never takes anything until the line is quiet: byte 1 is held, 49 are overruns.
  const auto never = [](std::size_t) { return false; };
  const auto r = play(s, never);
  ASSERT_EQ(r.bytes.size(), 1u);
  EXPECT_EQ(r.bytes[0], s.good_bytes[0]);
  EXPECT_EQ(r.overruns, 49);
  EXPECT_EQ(r.framing, 0);
}

}  // namespace
