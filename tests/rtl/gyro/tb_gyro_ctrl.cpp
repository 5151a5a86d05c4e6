// The gyro reader (rtl/gyro/gyro_ctrl.v with spi_master and gyro_accum, Verilated) against the C++
// model of the ICM-42688-P (sim/gyro/), pin by pin: start-up and configuration as the model's
// registers see them, every window's sum and count against the model's own log of the values the
// reader got (each sample in exactly one window, ticks also placed right on a sample's hand-over),
// and each fault (wrong ID, no data-ready, stuck value, invalid value) flagged, counted and not
// summed. The model also checks the reader's SPI timing (violations()).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "Vgyro_ctrl.h"
#include "omniloc_sim/icm42688.hpp"
#include "tb_clocked.hpp"
#include "tb_support.hpp"

namespace {

using omniloc::rtl_tb::Clocked;
using omniloc::sim::Icm42688;
using omniloc::sim::Icm42688Params;

constexpr double kClkHz = 12e6;
constexpr std::uint64_t kMs = 12000;  // cycles per millisecond
constexpr int kStuckN = 64;           // gyro_ctrl's STUCK_N default
constexpr std::uint64_t kLatency =
    8;  // cycles from the model's last SCLK edge to the hand-over, at most
constexpr unsigned kFlagId = 1, kFlagTimeout = 2, kFlagStuck = 4, kFlagInvalid = 8;

struct Window {
  std::int64_t sum;
  std::uint32_t count;
  std::uint32_t flags;
  std::uint32_t fault_count;
  std::uint64_t tick_cycle;  // the step index in which tick_i was high
};

class Bench {
 public:
  Bench(const Icm42688Params& params, Icm42688::RateFn rate) : model_(params, std::move(rate)) {
    dut_->rst_i = 1;
    cycle(false);
    cycle(false);
    dut_->rst_i = 0;
  }

  void cycle(bool tick) {
    const std::uint64_t index = model_.cycle();
    dut_->tick_i = tick ? 1 : 0;
    dut_->spi_miso_i = miso_ ? 1 : 0;
    dut_.step();
    miso_ = model_.step(dut_->spi_cs_n_o != 0, dut_->spi_sclk_o != 0, dut_->spi_mosi_o != 0);
    if (tick) last_tick_ = index;
    if (dut_->gyro_valid_o) {
      auto sum = static_cast<std::int64_t>(dut_->gyro_sum_o & 0xFFFFFFU);
      if (sum & 0x800000) sum -= 0x1000000;
      windows_.push_back(
          {sum, dut_->gyro_count_o, dut_->gyro_flags_o, dut_->gyro_fault_count_o, last_tick_});
    }
  }

  void run(std::uint64_t cycles) {
    for (std::uint64_t i = 0; i < cycles; ++i) cycle(false);
  }

  /// Windows of `period` cycles for `cycles` cycles (the first tick after one period).
  void run_windows(std::uint64_t cycles, std::uint64_t period) {
    for (std::uint64_t i = 1; i <= cycles; ++i) cycle(i % period == 0);
  }

  /// `n` windows of random length (3..17 ms); about a third end right around a sample's hand-over
  /// (1..6 cycles after the last SCLK edge of a Z burst, the hand-over is in that range).
  void run_random_windows(int n, std::mt19937_64& rng) {
    std::uniform_int_distribution<std::uint64_t> len(3 * kMs, 17 * kMs);
    std::uniform_int_distribution<int> off(1, 6);
    std::bernoulli_distribution near_sample(0.35);
    for (int w = 0; w < n; ++w) {
      std::uint64_t end = model_.cycle() + len(rng);
      if (near_sample(rng)) {
        const std::size_t reads = model_.reads().size();
        while (model_.reads().size() == reads) cycle(false);
        end = model_.reads().back().cycle + static_cast<std::uint64_t>(off(rng));
      }
      while (model_.cycle() < end) cycle(false);
      cycle(true);
    }
    cycle(false);
  }

  Vgyro_ctrl* operator->() { return dut_.operator->(); }
  Icm42688& model() { return model_; }
  const std::vector<Window>& windows() const { return windows_; }

 private:
  Clocked<Vgyro_ctrl> dut_;
  Icm42688 model_;
  bool miso_ = false;
  std::uint64_t last_tick_ = 0;
  std::vector<Window> windows_;
};

struct Accepted {
  std::vector<Icm42688::Sample> samples;
  int invalid = 0;
  int stuck = 0;
};

/// What the reader must accept of what it read: not 0x8000, and not the STUCK_N-th or later of a
/// run of identical values (the run's first value included; the reader's previous value starts 0).
Accepted accepted_of(const std::vector<Icm42688::Sample>& reads) {
  Accepted a;
  std::int16_t prev = 0;
  int run = 0;  // repeats of prev
  for (const auto& s : reads) {
    const bool invalid = s.value == INT16_MIN;
    const bool same = s.value == prev;
    const bool stuck = same && run >= kStuckN - 2;
    run = same ? std::min(run + 1, kStuckN - 1) : 0;
    prev = s.value;
    if (invalid) {
      ++a.invalid;
    } else if (stuck) {
      ++a.stuck;
    } else {
      a.samples.push_back(s);
    }
  }
  return a;
}

/// The windows partition the accepted samples in order: window k holds the next count_k of them,
/// its sum is theirs, each was read before its tick and after the previous tick (less the
/// hand-over latency); all samples read well before the last tick are in some window.
void expect_partition(const std::vector<Window>& windows,
                      const std::vector<Icm42688::Sample>& acc) {
  std::size_t next = 0;
  std::uint64_t prev_tick = 0;
  for (std::size_t k = 0; k < windows.size(); ++k) {
    const Window& w = windows[k];
    ASSERT_LE(next + w.count, acc.size()) << "window " << k << " holds more samples than were read";
    std::int64_t sum = 0;
    for (std::uint32_t i = 0; i < w.count; ++i) {
      const auto& s = acc[next + i];
      sum += s.value;
      EXPECT_LT(s.cycle, w.tick_cycle)
          << "window " << k << " sample " << i << " read after the tick";
      EXPECT_GE(s.cycle + kLatency, prev_tick)
          << "window " << k << " sample " << i << " belongs to an earlier window";
    }
    EXPECT_EQ(w.sum, sum) << "window " << k << " (" << w.count << " samples)";
    next += w.count;
    prev_tick = w.tick_cycle;
  }
  std::size_t settled = 0;  // samples read before the last tick less the latency
  for (const auto& s : acc) {
    if (s.cycle + kLatency < prev_tick) ++settled;
  }
  EXPECT_GE(next, settled) << "samples read before the last tick are missing from the windows";
}

double sine_rate(double t) {
  return 90.0 * std::sin(2.0 * M_PI * 0.7 * t) + 20.0 * std::cos(2.0 * M_PI * 3.1 * t);
}

TEST(GyroCtrl, StartupChecksTheIdAndConfiguresThePart) {
  Bench b({kClkHz, 0.0, 0.0, 0.030, 1}, [](double) { return 0.0; });
  b.run(40 * kMs);
  auto& m = b.model();
  EXPECT_TRUE(m.violations().empty()) << m.violations().front();
  EXPECT_EQ(m.soft_resets(), 1);
  EXPECT_EQ(m.who_am_i_reads(), 1);
  EXPECT_EQ(m.reg(Icm42688::kPwrMgmt0), 0x0C);     // gyro low-noise mode
  EXPECT_EQ(m.reg(Icm42688::kGyroConfig0), 0x06);  // +-2000 dps, 1 kHz
  EXPECT_DOUBLE_EQ(m.odr_hz(), 1000.0);
  EXPECT_DOUBLE_EQ(m.sensitivity_lsb_per_dps(), 16.4);
  EXPECT_TRUE(b->gyro_running_o);
  EXPECT_FALSE(b->gyro_id_fault_o);
  EXPECT_GE(m.reads().size(), 8U);  // data from 31.2 ms on (1.2 ms of waits + 30 ms start-up)
  EXPECT_EQ(b->gyro_fault_count_o, 0U);
}

TEST(GyroCtrl, ConstantRateGivesTheHandComputedSum) {
  // 123.4 deg/s at 16.4 LSB/(deg/s) = 2023.76: every sample reads 2024. Noise-free, so the values
  // are identical: the first 63 are summed, from the 64th (STUCK_N) on they count as stuck.
  Bench b({kClkHz, 0.0, 0.0, 0.030, 1}, [](double) { return 123.4; });
  b.run_windows(40 * kMs, 40 * kMs);  // the first window, to 40 ms: samples from 31.2 ms on
  ASSERT_EQ(b.windows().size(), 1U);
  const std::uint32_t first = b.windows()[0].count;
  EXPECT_GE(first, 8U);
  EXPECT_LE(first, 9U);
  EXPECT_EQ(b.windows()[0].sum, 2024 * static_cast<std::int64_t>(first));
  b.run_windows(50 * kMs, 10 * kMs);
  ASSERT_EQ(b.windows().size(), 6U);
  for (std::size_t k = 1; k < 6; ++k) {
    const Window& w = b.windows()[k];
    EXPECT_EQ(w.count, 10U);  // 1 kHz in 10 ms windows
    EXPECT_EQ(w.sum, 2024 * 10);
    EXPECT_EQ(w.flags, 0U);
  }
  b.run_windows(20 * kMs, 10 * kMs);  // the run reaches 64 identical samples: the rest are stuck
  ASSERT_EQ(b.windows().size(), 8U);
  const Window& w6 = b.windows()[6];
  EXPECT_EQ(w6.flags, kFlagStuck);
  EXPECT_EQ(first + 50 + w6.count, 63U);  // exactly STUCK_N - 1 samples summed
  EXPECT_EQ(w6.sum, 2024 * static_cast<std::int64_t>(w6.count));
  EXPECT_EQ(b.windows()[7].count, 0U);
  EXPECT_EQ(b->gyro_fault_count_o, 10U - w6.count + 10U);
}

TEST(GyroCtrl, EverySampleLandsInExactlyOneWindow) {
  const std::uint64_t seed =
      omniloc::rtl_tb::test_seed("GyroCtrl.EverySampleLandsInExactlyOneWindow", 42);
  std::mt19937_64 rng(seed);
  Bench b({kClkHz, 0.7, 0.3, 0.030, seed}, sine_rate);
  b.run(35 * kMs);
  b.run_random_windows(90, rng);
  auto& m = b.model();
  EXPECT_TRUE(m.violations().empty()) << m.violations().front();
  // Each produced sample was read exactly once, in order (the latest may still be unread).
  ASSERT_LE(m.reads().size(), m.produced().size());
  ASSERT_GE(m.reads().size() + 1, m.produced().size());
  for (std::size_t i = 0; i < m.reads().size(); ++i) {
    ASSERT_EQ(m.reads()[i].value, m.produced()[i].value) << "sample " << i;
  }
  const Accepted acc = accepted_of(m.reads());
  EXPECT_EQ(acc.invalid + acc.stuck, 0);
  ASSERT_EQ(b.windows().size(), 90U);
  expect_partition(b.windows(), acc.samples);
  std::uint64_t total = 0;
  for (const auto& w : b.windows()) {
    EXPECT_EQ(w.flags, 0U);
    total += w.count;
  }
  EXPECT_GT(total, 500U);
  EXPECT_EQ(b->gyro_fault_count_o, 0U);
}

TEST(GyroCtrl, WrongIdIsAFaultRetriedEvery100Ms) {
  Bench b({kClkHz, 0.0, 0.5, 0.030, 1}, [](double) { return 10.0; });
  b.model().faults().who_am_i = 0x12;
  b.run_windows(350 * kMs, 10 * kMs);
  auto& m = b.model();
  EXPECT_EQ(m.who_am_i_reads(), 4);  // at 1 ms, then every 101 ms
  EXPECT_EQ(m.soft_resets(), 4);
  EXPECT_EQ(m.reg(Icm42688::kPwrMgmt0), 0x00) << "the gyro was switched on with a wrong ID";
  EXPECT_TRUE(b->gyro_id_fault_o);
  EXPECT_FALSE(b->gyro_running_o);
  EXPECT_EQ(b->gyro_fault_count_o, 4U);
  int flagged = 0;
  for (const auto& w : b.windows()) {
    EXPECT_EQ(w.count, 0U);
    EXPECT_EQ(w.sum, 0);
    if (w.flags & kFlagId) ++flagged;
    EXPECT_EQ(w.flags & ~kFlagId, 0U);
  }
  EXPECT_EQ(flagged, 4);
  // The genuine part answers: running after the next retry, samples summed.
  m.faults().who_am_i = 0x47;
  b.run_windows(150 * kMs, 10 * kMs);
  EXPECT_TRUE(b->gyro_running_o);
  EXPECT_EQ(b.windows().back().count, 10U);
  EXPECT_NEAR(static_cast<double>(b.windows().back().sum), 164.0 * 10,
              150.0);  // 10 dps, noise 8 LSB rms
  EXPECT_EQ(b->gyro_fault_count_o, 4U);
  EXPECT_TRUE(m.violations().empty()) << m.violations().front();
}

TEST(GyroCtrl, NoDataReadyIsATimeoutAndARestart) {
  Bench b({kClkHz, 0.0, 0.2, 0.030, 7}, sine_rate);
  b.run(35 * kMs);
  b.run_windows(30 * kMs, 10 * kMs);
  auto& m = b.model();
  m.faults().no_data_ready = true;
  b.run_windows(20 * kMs, 10 * kMs);
  m.faults().no_data_ready = false;
  b.run_windows(60 * kMs, 10 * kMs);
  EXPECT_EQ(m.soft_resets(), 2);  // the start-up once more after the timeout
  EXPECT_EQ(b->gyro_fault_count_o, 1U);
  EXPECT_TRUE(b->gyro_running_o);
  int flagged = 0;
  for (const auto& w : b.windows()) {
    if (w.flags & kFlagTimeout) ++flagged;
  }
  EXPECT_EQ(flagged, 1);
  const Accepted acc = accepted_of(m.reads());
  expect_partition(b.windows(), acc.samples);
  EXPECT_EQ(b.windows().back().count, 10U);
  EXPECT_TRUE(m.violations().empty()) << m.violations().front();
}

TEST(GyroCtrl, StuckValueIsRejectedFromTheNthRepeat) {
  Bench b({kClkHz, 0.0, 0.5, 0.030, 3}, sine_rate);
  b.run(35 * kMs);
  b.run_windows(20 * kMs, 10 * kMs);
  auto& m = b.model();
  m.faults().stuck = true;
  b.run_windows(200 * kMs, 10 * kMs);
  m.faults().stuck = false;
  b.run_windows(30 * kMs, 10 * kMs);
  const Accepted acc = accepted_of(m.reads());
  // The run is about 200 samples long (one more if the last good value equals nothing before).
  EXPECT_GE(acc.stuck, 200 - kStuckN);
  EXPECT_LE(acc.stuck, 202 - kStuckN + 1);
  EXPECT_EQ(b->gyro_fault_count_o, std::min(255U, static_cast<unsigned>(acc.stuck)));
  expect_partition(b.windows(), acc.samples);
  int flagged = 0;
  for (const auto& w : b.windows()) {
    if (w.flags & kFlagStuck) ++flagged;
    EXPECT_EQ(w.flags & ~kFlagStuck, 0U);
  }
  EXPECT_GE(flagged, 13);  // ~137 stuck samples at 10 a window
  EXPECT_EQ(b.windows().back().count, 10U);
}

TEST(GyroCtrl, InvalidValueIsRejected) {
  Bench b({kClkHz, 0.0, 0.5, 0.030, 5}, sine_rate);
  b.run(35 * kMs);
  b.run_windows(20 * kMs, 10 * kMs);
  auto& m = b.model();
  m.faults().invalid = true;
  b.run(5 * kMs);  // about five samples of 0x8000, within one window
  m.faults().invalid = false;
  b.run_windows(30 * kMs, 10 * kMs);
  const Accepted acc = accepted_of(m.reads());
  EXPECT_GE(acc.invalid, 4);
  EXPECT_LE(acc.invalid, 6);
  EXPECT_EQ(acc.stuck, 0);
  EXPECT_EQ(b->gyro_fault_count_o, static_cast<unsigned>(acc.invalid));
  expect_partition(b.windows(), acc.samples);
  int flagged = 0;
  for (const auto& w : b.windows()) {
    if (w.flags & kFlagInvalid) ++flagged;
  }
  EXPECT_EQ(flagged, 1);
}

}  // namespace
