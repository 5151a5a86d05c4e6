// The whole board (rtl/omniloc_top.v: encoder core + UART link) through its pins: the host's own
// protocol code (BoardClient over SimTransport) talks to it bit by bit at 1 Mbaud while the world
// simulator's quadrature waveforms run on all four encoders. Every streamed window must equal the
// golden count: an x4 decoder run over the very levels the board was given.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "omniloc/board_client.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "omniloc_sim/world.hpp"
#include "tb_util.hpp"

namespace {

namespace rm = omniloc::regmap;
using omniloc::sim::BoardSim;
constexpr std::int64_t kCaptureLag = 4;

// Passes the stream's levels to the board and keeps, for the last kRing cycles, the cumulative
// x4 count of each encoder: the golden model the board's windows are checked against.
class RecordingSource final : public omniloc::sim::EncoderSource {
 public:
  static constexpr std::int64_t kRing = 1 << 19;

  explicit RecordingSource(omniloc::sim::QuadratureStream& stream)
      : stream_(stream), ring_(static_cast<std::size_t>(kRing)) {}

  void fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out) override {
    stream_.fill_levels(first_cycle, out);
    for (std::size_t i = 0; i < out.size(); ++i) {
      for (int m = 0; m < 4; ++m) {
        const int a = (out[i] >> (2 * m)) & 1;
        const int b = (out[i] >> (2 * m + 1)) & 1;
        const int phase = b ? (a ? 2 : 3) : (a ? 1 : 0);  // AB = 00, 10, 11, 01
        const int step = (phase - phase_[m] + 4) % 4;
        if (step == 1) ++count_[m];
        if (step == 3) --count_[m];
        if (step == 2) ++illegal_;
        phase_[m] = phase;
      }
      ring_[static_cast<std::size_t>((first_cycle + static_cast<std::int64_t>(i)) % kRing)] = count_;
      last_cycle_ = first_cycle + static_cast<std::int64_t>(i);
    }
  }

  /// Cumulative counts as they stood at `cycle` (which must be within the last kRing cycles).
  [[nodiscard]] std::array<std::int64_t, 4> counts_at(std::int64_t cycle) const {
    EXPECT_GT(cycle, last_cycle_ - kRing);
    EXPECT_LE(cycle, last_cycle_);
    return ring_[static_cast<std::size_t>(cycle % kRing)];
  }
  [[nodiscard]] int illegal() const { return illegal_; }
  [[nodiscard]] std::array<std::int64_t, 4> total() const { return count_; }

 private:
  omniloc::sim::QuadratureStream& stream_;
  std::vector<std::array<std::int64_t, 4>> ring_;
  std::array<std::int64_t, 4> count_{};
  std::array<int, 4> phase_{};
  std::int64_t last_cycle_ = -1;
  int illegal_ = 0;
};

omniloc::sim::WorldConfig board_world(std::uint64_t seed) {
  auto robot = omniloc::load_named_robot_config("default");
  robot.clock_hz = static_cast<double>(BoardSim::kClockHz);
  auto config = omniloc::sim::WorldConfig::noise_free(robot, seed);
  config.step_cycles = BoardSim::kClockHz / 1000;
  config.window_cycles = BoardSim::kClockHz / 100;
  config.first_window_end_cycles = config.window_cycles;
  config.random_encoder_phase = false;  // the board's decoders start from AB = 00 after reset
  return config;
}

TEST(OmnilocTop, RegistersErrorsAndStreamedWindowsThroughTheUartPins) {
  const auto seed = omniloc::tb::test_seed(61);
  omniloc::sim::QuadratureStream stream(board_world(seed), omniloc::sim::make_trajectory("figure_eight", seed));
  RecordingSource source(stream);
  BoardSim board(&source);
  omniloc::sim::SimTransport transport(board);
  omniloc::BoardClient client(transport);

  // Identity, over the wire.
  EXPECT_EQ(client.read_register(rm::kRegId), rm::kIdValue);
  EXPECT_EQ(client.read_register(rm::kRegVersion), rm::kVersionValue);

  // Error answers: a read-only register, an unknown address, a refused value.
  try {
    client.write_register(rm::kRegId, 1);
    ADD_FAILURE() << "a write to ID was accepted";
  } catch (const omniloc::BoardError& e) {
    EXPECT_EQ(e.error_code(), rm::kErrReadOnly);
  }
  try {
    (void)client.read_register(0x7F);
    ADD_FAILURE() << "a read of 0x7F was accepted";
  } catch (const omniloc::BoardError& e) {
    EXPECT_EQ(e.error_code(), rm::kErrBadAddress);
  }
  try {
    client.write_register(rm::kRegPeriod, 3);
    ADD_FAILURE() << "PERIOD = 3 was accepted";
  } catch (const omniloc::BoardError& e) {
    EXPECT_EQ(e.error_code(), rm::kErrBadValue);
  }
  EXPECT_EQ(client.read_register(rm::kRegPeriod), static_cast<std::uint32_t>(BoardSim::kClockHz / 100));

  // Enable x4 counting and streaming; read the control register back.
  std::uint32_t control = 0;
  control = rm::kControlEnable.put(control, 1);
  control = rm::kControlDecode.put(control, rm::kControlDecodeX4);
  control = rm::kControlStream.put(control, 1);
  client.write_register(rm::kRegControl, control);
  EXPECT_EQ(client.read_register(rm::kRegControl), control);

  // A second of streamed windows. A window stamped T counts the pin levels up to cycle
  // T - kCaptureLag of the source (docs/RTL.md: pin -> window counter is max(FILTER, 1) + 3 = 4
  // cycles with the filter off, and the timestamp is 0 in the last reset cycle).
  std::vector<omniloc::protocol::Window> windows;
  int checked = 0, moving = 0;
  std::array<std::int64_t, 4> streamed_sum{};
  while (windows.size() < 101) {
    const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
    ASSERT_TRUE(w.has_value()) << "no telemetry within 100 ms after " << windows.size() << " windows";
    windows.push_back(*w);
    if (windows.size() < 2) continue;
    const auto& cur = windows.back();
    const auto& prev = windows[windows.size() - 2];
    ASSERT_EQ(cur.seq, prev.seq + 1) << "a window was lost";
    ASSERT_EQ(cur.timestamp_cycles - prev.timestamp_cycles, BoardSim::kClockHz / 100) << "window period";
    const auto end = static_cast<std::int64_t>(cur.timestamp_cycles);
    const auto begin = static_cast<std::int64_t>(prev.timestamp_cycles);
    const auto e = source.counts_at(end - kCaptureLag);
    const auto b = source.counts_at(begin - kCaptureLag);
    for (int m = 0; m < 4; ++m) {
      ASSERT_EQ(cur.count[m], e[m] - b[m]) << "window " << cur.seq << " motor " << m + 1;
      streamed_sum[m] += cur.count[m];
      moving += cur.count[m] != 0;
    }
    ++checked;
  }
  std::printf("%d windows checked against the golden decoder, %d motor-windows moving; sums %lld %lld %lld %lld\n",
              checked, moving, static_cast<long long>(streamed_sum[0]), static_cast<long long>(streamed_sum[1]),
              static_cast<long long>(streamed_sum[2]), static_cast<long long>(streamed_sum[3]));
  EXPECT_GE(checked, 90);
  EXPECT_GE(moving, 200);
  EXPECT_EQ(source.illegal(), 0);
  EXPECT_EQ(board.counters().tx_framing_errors, 0u);
  EXPECT_EQ(client.decoder_counters().bad_crc, 0u);

  // A snapshot is the latest window, whole.
  const auto snap = client.snapshot();
  EXPECT_GE(snap.seq, windows.back().seq);
}

}  // namespace
