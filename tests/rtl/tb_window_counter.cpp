// window_counter testbench: random up/down pulses and captures (also in the same cycle) against
// a golden running sum; every captured window, the position and their conservation are checked.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>

#include <Vwindow_counter.h>

#include "tb_clocked.hpp"

namespace {

using omniloc::rtl_tb::Clocked;

struct Result {
  std::string failure;
  std::uint64_t fail_cycle = 0;
  std::uint64_t captures = 0;
  std::uint64_t pulses_in_capture_cycle = 0;
};

Result run(std::uint64_t seed, int cycles, const omniloc::rtl_tb::TraceRequest* trace) {
  std::mt19937_64 rng(seed);
  Result res;
  Clocked<Vwindow_counter> dut(trace);
  dut->up_i = 0;
  dut->down_i = 0;
  dut->capture_i = 0;
  dut.reset(2);
  std::int64_t running = 0;    // golden count of the open window
  std::uint32_t position = 0;  // golden position
  std::int64_t window = 0;
  std::uint32_t window_pos = 0;
  bool window_dir = false;
  std::int64_t sum_of_windows = 0;
  // Phases of steady drift up, drift down, and noise, so the count crosses zero and wraps.
  for (int i = 0; i < cycles; ++i) {
    const int phase = (i / 50'000) % 3;
    const unsigned r = static_cast<unsigned>(rng() % 100);
    const bool up = phase == 0 ? r < 70 : (phase == 1 ? r < 5 : r < 40);
    const bool down = !up && (phase == 1 ? r < 75 : (phase == 0 ? r < 75 : r < 80));
    const bool dir = static_cast<bool>(rng() & 1);
    const bool capture = (rng() % 61) == 0;
    dut->up_i = up;
    dut->down_i = down;
    dut->dir_i = dir;
    dut->capture_i = capture;
    const std::uint64_t e = dut.cycle();
    dut.step();
    const int delta = up ? 1 : (down ? -1 : 0);
    running += delta;
    position += static_cast<std::uint32_t>(delta);
    if (capture) {
      window = running;
      window_pos = position;
      window_dir = dir;
      sum_of_windows += running;
      running = 0;
      ++res.captures;
      res.pulses_in_capture_cycle += (delta != 0);
    }
    std::string what;
    if (static_cast<std::int32_t>(dut->win_count_o) != window)
      what = "win_count_o";
    else if (dut->win_position_o != window_pos)
      what = "win_position_o";
    else if ((dut->win_dir_o != 0) != window_dir)
      what = "win_dir_o";
    else if (dut->position_o != position)
      what = "position_o";
    // Conservation: what was captured plus what is open is all there was.
    else if (static_cast<std::uint32_t>(sum_of_windows + running) != position)
      what = "golden conservation";
    if (!what.empty()) {
      res.failure = what + " differs from the golden model at edge " + std::to_string(e);
      res.fail_cycle = e;
      return res;
    }
  }
  return res;
}

TEST(WindowCounter, CapturesEveryPulseExactlyOnce) {
  const std::uint64_t seed = omniloc::rtl_tb::test_seed("window_counter", 31337);
  const auto res = run(seed, 3'000'000, nullptr);
  std::cout << "[window_counter] captures=" << res.captures
            << " pulses in a capture cycle=" << res.pulses_in_capture_cycle << "\n";
  if (!res.failure.empty()) {
    const omniloc::rtl_tb::TraceRequest tr{omniloc::rtl_tb::trace_path("window_counter", seed),
                                           res.fail_cycle > 2000 ? res.fail_cycle - 2000 : 0};
    run(seed, static_cast<int>(res.fail_cycle), &tr);
    FAIL() << res.failure << " seed " << seed << "; trace: " << tr.path;
  }
  EXPECT_GT(res.pulses_in_capture_cycle, 1000u);
}

TEST(WindowCounter, PositionWrapsAt32Bits) {
  Clocked<Vwindow_counter> dut;
  dut->up_i = 0;
  dut->down_i = 1;
  dut->capture_i = 0;
  dut.reset(2);
  for (int i = 0; i < 3; ++i) dut.step();
  dut->down_i = 0;
  dut->capture_i = 1;
  dut.step();
  EXPECT_EQ(dut->position_o, 0xFFFFFFFDu);
  EXPECT_EQ(dut->win_position_o, 0xFFFFFFFDu);
  EXPECT_EQ(static_cast<std::int32_t>(dut->win_count_o), -3);
}

}  // namespace
