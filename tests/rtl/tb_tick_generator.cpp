// tick_generator testbench: exact tick spacing at the 40 MHz / 100 Hz defaults over many windows,
// and run-time period changes that take effect at the next tick, against a golden schedule.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>

#include <Vtick_generator.h>

#include "tb_clocked.hpp"

namespace {

using omniloc::rtl_tb::Clocked;
using omniloc::rtl_tb::TraceRequest;
constexpr std::uint64_t kDefaultPeriodCycles = 40'000'000 / 100;

struct Result {
  std::string failure;
  std::uint64_t fail_cycle = 0;
};

Result fail_at(std::uint64_t e, const std::string& what) {
  return {what + " at edge " + std::to_string(e), e};
}

Result run_defaults(int windows, const TraceRequest* trace) {
  Clocked<Vtick_generator> dut(trace);
  dut->period_i = kDefaultPeriodCycles;
  dut.reset(2);
  const std::uint64_t first_edge = dut.cycle();
  std::uint64_t last_tick = 0;
  int ticks = 0;
  while (ticks < windows) {
    const std::uint64_t e = dut.cycle();
    dut.step();
    // Timestamp counts edges since reset: 1 after the first.
    if (dut->timestamp_o != static_cast<std::uint32_t>(e - first_edge + 1))
      return fail_at(e, "timestamp_o wrong");
    if (dut->tick_o) {
      const std::uint64_t golden =
          ticks == 0 ? first_edge + kDefaultPeriodCycles - 1 : last_tick + kDefaultPeriodCycles;
      if (e != golden)
        return fail_at(e,
                       "tick " + std::to_string(ticks) + " expected at " + std::to_string(golden));
      last_tick = e;
      ++ticks;
    } else if (e == (ticks == 0 ? first_edge + kDefaultPeriodCycles - 1
                                : last_tick + kDefaultPeriodCycles)) {
      return fail_at(e, "missing tick " + std::to_string(ticks));
    }
  }
  if (dut->period_o != kDefaultPeriodCycles) return fail_at(dut.cycle(), "period_o wrong");
  return {};
}

TEST(TickGenerator, ExactPeriodAtDefaultsOver50Windows) {
  const auto res = run_defaults(50, nullptr);
  if (!res.failure.empty()) {
    const TraceRequest tr{omniloc::rtl_tb::trace_path("tick_generator_defaults", 0),
                          res.fail_cycle > 3000 ? res.fail_cycle - 3000 : 0};
    run_defaults(static_cast<int>(res.fail_cycle / kDefaultPeriodCycles) + 1, &tr);
    FAIL() << res.failure << "; trace: " << tr.path;
  }
}

Result run_changes(std::uint64_t seed, int windows, const TraceRequest* trace) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::uint32_t> period_dist(2, 300);
  Clocked<Vtick_generator> dut(trace);
  std::uint32_t requested = period_dist(rng);
  dut->period_i = requested;
  dut.reset(2);
  // Golden: the first window has the reset period; the tick edge reloads the counter with the
  // period presented at that edge, which is the next window's length.
  std::uint64_t next_tick = dut.cycle() + kDefaultPeriodCycles - 1;
  int ticks = 0;
  while (ticks < windows) {
    // Change the request at random moments, also in the tick cycle itself.
    if (rng() % 97 == 0) requested = period_dist(rng);
    dut->period_i = requested;
    const std::uint64_t e = dut.cycle();
    dut.step();
    const bool golden_tick = (e == next_tick);
    if ((dut->tick_o != 0) != golden_tick)
      return fail_at(e, "tick_o " + std::to_string(dut->tick_o));
    if (golden_tick) {
      ++ticks;
      if (dut->period_o != requested)
        return fail_at(e, "period_o not the period sampled at the tick");
      next_tick = e + requested;
    }
  }
  return {};
}

TEST(TickGenerator, PeriodChangesTakeEffectAtTheNextTick) {
  const std::uint64_t seed = omniloc::rtl_tb::test_seed("tick_generator_period_changes", 4242);
  const auto res = run_changes(seed, 5000, nullptr);
  if (!res.failure.empty()) {
    const TraceRequest tr{omniloc::rtl_tb::trace_path("tick_generator_period_changes", seed),
                          res.fail_cycle > 3000 ? res.fail_cycle - 3000 : 0};
    run_changes(seed, 5000, &tr);
    FAIL() << res.failure << " seed " << seed << "; trace: " << tr.path;
  }
}

}  // namespace
