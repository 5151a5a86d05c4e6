// The whole board (rtl/omniloc_top.v: encoder core + UART link) through its pins: the host's own
// protocol code (BoardClient over SimTransport) talks to it bit by bit at 1 Mbaud while the world
// simulator's quadrature waveforms run on all four encoders. Every streamed window must equal the
// golden count: an x4 decoder run over the very levels the board was given.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <random>
#include <vector>

#include "golden_quadrature.hpp"
#include "omniloc/board_client.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "omniloc_sim/icm42688.hpp"
#include "omniloc_sim/link_faults.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "omniloc_sim/world.hpp"
#include "tb_support.hpp"

namespace {

namespace rm = omniloc::regmap;
using omniloc::sim::BoardSim;
constexpr std::int64_t kCaptureLag = 4;

TEST(OmnilocTop, RegistersErrorsAndStreamedWindowsThroughTheUartPins) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 61);
  omniloc::sim::QuadratureStream stream(omniloc::tb::board_world(seed),
                                        omniloc::sim::make_trajectory("figure_eight", seed));
  omniloc::tb::GoldenQuadrature source(stream, BoardSim::kClockHz / 100);
  BoardSim board(&source);
  omniloc::sim::SimTransport transport(board);
  omniloc::BoardClient client(transport);

  // Identity, over the wire.
  EXPECT_EQ(client.read_register(rm::kRegId), rm::kIdValue);
  EXPECT_EQ(client.read_register(rm::kRegVersion), rm::kVersionValue);
  EXPECT_EQ(client.read_register(rm::kRegConfig), 4u)
      << "CONFIG.CHANNELS of the default board: four wheels";

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
  EXPECT_EQ(client.read_register(rm::kRegPeriod),
            static_cast<std::uint32_t>(BoardSim::kClockHz / 100));

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
    ASSERT_TRUE(w.has_value()) << "no telemetry within 100 ms after " << windows.size()
                               << " windows";
    windows.push_back(*w);
    if (windows.size() < 2) continue;
    const auto& cur = windows.back();
    const auto& prev = windows[windows.size() - 2];
    ASSERT_EQ(cur.seq, prev.seq + 1) << "a window was lost";
    ASSERT_EQ(cur.timestamp_cycles - prev.timestamp_cycles, BoardSim::kClockHz / 100)
        << "window period";
    const auto end = static_cast<std::int64_t>(cur.timestamp_cycles);
    const auto begin = static_cast<std::int64_t>(prev.timestamp_cycles);
    const auto e = source.counts_at(end - kCaptureLag);
    const auto b = source.counts_at(begin - kCaptureLag);
    ASSERT_TRUE(e && b) << "window " << cur.seq << " ends at cycle " << end
                        << ", not at a window boundary";
    for (int m = 0; m < 4; ++m) {
      ASSERT_EQ(cur.count[m], (*e)[m] - (*b)[m]) << "window " << cur.seq << " motor " << m + 1;
      streamed_sum[m] += cur.count[m];
      moving += cur.count[m] != 0;
    }
    ++checked;
  }
  std::printf(
      "%d windows checked against the golden decoder, %d motor-windows moving; sums %lld %lld %lld "
      "%lld\n",
      checked, moving, static_cast<long long>(streamed_sum[0]),
      static_cast<long long>(streamed_sum[1]), static_cast<long long>(streamed_sum[2]),
      static_cast<long long>(streamed_sum[3]));
  EXPECT_GE(checked, 90);
  EXPECT_GE(moving, 200);
  EXPECT_EQ(source.illegal(), 0);
  EXPECT_EQ(board.counters().tx_framing_errors, 0u);
  EXPECT_EQ(client.decoder_counters().bad_crc, 0u);

  // A snapshot is the latest window, whole.
  const auto snap = client.snapshot();
  EXPECT_GE(snap.seq, windows.back().seq);
}

// The host's transport onto the board through a faulty line: bytes corrupted, dropped and cut off
// in both directions. read() runs the board until bytes come through or the timeout has passed.
class FaultyBoardTransport final : public omniloc::Transport {
 public:
  FaultyBoardTransport(BoardSim& board, omniloc::sim::FaultyUart& line)
      : board_(board), line_(line) {}
  void write(std::span<const std::uint8_t> bytes) override { line_.to_board(bytes); }
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override {
    const std::int64_t deadline = board_.cycle() + timeout.count() * (BoardSim::kClockHz / 1000);
    std::size_t n = line_.from_board(out);
    while (n == 0 && board_.cycle() < deadline) {
      board_.run_cycles(BoardSim::kClockHz / 10'000);
      n = line_.from_board(out);
    }
    return n;
  }
  [[nodiscard]] omniloc::TransportStatus status() const override {
    return {true, false, "faulty line", {}};
  }
  [[nodiscard]] std::chrono::steady_clock::time_point now() const override {
    return omniloc::sim::board_time(board_);
  }

 private:
  BoardSim& board_;
  omniloc::sim::FaultyUart& line_;
};

TEST(OmnilocTop, FaultyLineNeverDeliversACorruptWindowOrRegister) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 62);
  omniloc::sim::QuadratureStream stream(omniloc::tb::board_world(seed),
                                        omniloc::sim::make_trajectory("random_walk", seed));
  omniloc::tb::GoldenQuadrature golden(stream, BoardSim::kClockHz / 100);
  BoardSim board(&golden);
  omniloc::sim::FaultRates rates;
  rates.corrupt_per_byte = 1e-3;
  rates.drop_per_byte = 1e-3;
  rates.truncate_per_byte = 1e-3;
  omniloc::sim::FaultyUart line(board, rates, rates, seed);
  FaultyBoardTransport transport(board, line);
  omniloc::BoardClientOptions options;
  options.attempts = 8;
  omniloc::BoardClient client(transport, options);

  std::uint32_t control = rm::kControlEnable.put(0, 1);
  control = rm::kControlDecode.put(control, rm::kControlDecodeX4);
  control = rm::kControlStream.put(control, 1);
  client.write_register(rm::kRegControl, control);

  std::mt19937_64 rng(seed);
  std::optional<omniloc::protocol::Window> prev;
  std::uint32_t filter = 0;
  int accepted = 0, lost = 0, register_checks = 0;
  while (accepted < 200) {
    const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
    if (!w.has_value()) {
      const auto& d = client.decoder_counters();
      ADD_FAILURE() << "the stream stopped after " << accepted << " windows at board cycle "
                    << board.cycle() << "; frames ok " << d.frames_ok << ", bad CRC " << d.bad_crc
                    << ", bad length " << d.bad_length << ", resync bytes " << d.resync_bytes
                    << ", bytes pending on the board side " << board.pending_from_board()
                    << ", to the board " << board.counters().bytes_to_board << ", from the board "
                    << board.counters().bytes_from_board;
      return;
    }
    ++accepted;
    if (prev && w->seq > prev->seq) {
      lost += static_cast<int>(w->seq - prev->seq - 1);
      // Every window that arrives is whole: it equals the golden count over its own span.
      const std::uint32_t windows = w->seq - prev->seq;
      ASSERT_EQ(w->timestamp_cycles - prev->timestamp_cycles,
                windows * static_cast<std::uint32_t>(BoardSim::kClockHz / 100));
      const auto e = golden.counts_at(static_cast<std::int64_t>(w->timestamp_cycles) - kCaptureLag);
      const auto b = golden.counts_at(static_cast<std::int64_t>(w->timestamp_cycles) - kCaptureLag -
                                      BoardSim::kClockHz / 100);
      ASSERT_TRUE(e && b);
      for (int m = 0; m < 4; ++m)
        ASSERT_EQ(w->count[m], (*e)[m] - (*b)[m]) << "window " << w->seq << " motor " << m + 1;
    }
    prev = w;
    // Now and then a write and a read back through the same faulty line: a value the host accepts
    // is the value the board holds.
    if (accepted % 10 == 0) {
      // FILTER 0 and 1 both mean a 4-cycle pin-to-count latency, the lag the golden check uses.
      filter = static_cast<std::uint32_t>(rng() % 2);
      client.write_register(rm::kRegFilter, filter);
      ASSERT_EQ(client.read_register(rm::kRegFilter), filter);
      ASSERT_EQ(client.read_register(rm::kRegControl), control);
      ++register_checks;
    }
  }
  line.set_enabled(false);
  const std::uint32_t link_errors = client.read_register(rm::kRegLinkErrors);
  // Drain what the register traffic buffered: the decoder counts a gap when it decodes the window
  // after it, which may be one the loop above did not take yet.
  for (int i = 0; i < 5; ++i) {
    const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
    ASSERT_TRUE(w.has_value());
    if (prev && w->seq > prev->seq) lost += static_cast<int>(w->seq - prev->seq - 1);
    prev = w;
  }
  const auto& faults_to = line.to_board_log();
  const auto& faults_from = line.from_board_log();
  const auto& dc = client.decoder_counters();
  std::printf(
      "%d windows accepted, %d lost (decoder counted %llu); %d register write/read checks, %llu "
      "retries; "
      "faults: to board %llu corrupt %llu dropped, from board %llu corrupt %llu dropped; "
      "LINK_ERRORS 0x%08X\n",
      accepted, lost, static_cast<unsigned long long>(dc.telemetry_lost), register_checks,
      static_cast<unsigned long long>(client.counters().retries),
      static_cast<unsigned long long>(faults_to.corrupted),
      static_cast<unsigned long long>(faults_to.dropped),
      static_cast<unsigned long long>(faults_from.corrupted),
      static_cast<unsigned long long>(faults_from.dropped), link_errors);
  // Every loss shows in the counters.
  EXPECT_EQ(static_cast<std::uint64_t>(lost), dc.telemetry_lost);
  EXPECT_GT(faults_to.corrupted + faults_to.dropped, 0u);
  EXPECT_GT(faults_from.corrupted + faults_from.dropped, 0u);
  EXPECT_EQ(golden.illegal(), 0);
}

// Issue 35, item 1: the gyro in the board. The ICM-42688-P model on the SPI pins (a yaw rate that
// sweeps +-300 deg/s, noise 0.16 deg/s rms) against the windows streamed over the UART: every
// sample the model handed out is in exactly one window, in order, each window's gyro_sum the exact
// sum of its samples (the model's read log is the reference); GYRO_STATE says running; the
// snapshot registers read the same window as the snapshot body. Then the part goes silent (its
// data-ready stops): the windows are flagged, STATUS.GYRO_FAULT is set, and it recovers.
TEST(OmnilocTop, GyroSamplesLandInTheWindowsExactlyOnce) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 35);
  omniloc::sim::Icm42688Params gp;
  gp.clk_hz = static_cast<double>(BoardSim::kClockHz);
  gp.noise_dps_rms = 0.16;
  gp.bias_dps = 0.3;
  gp.seed = seed;
  omniloc::sim::Icm42688 gyro(
      gp, [](double t) { return 300.0 * std::sin(2.0 * 3.14159265358979 * 1.3 * t); });
  BoardSim board(nullptr, &gyro);
  omniloc::sim::SimTransport transport(board);
  omniloc::BoardClient client(transport);
  std::uint32_t control = rm::kControlEnable.put(0, 1);
  control = rm::kControlStream.put(control, 1);
  client.write_register(rm::kRegControl, control);

  std::vector<omniloc::protocol::Window> windows;
  while (windows.size() < 120) {
    const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
    ASSERT_TRUE(w.has_value()) << "no telemetry after " << windows.size() << " windows";
    windows.push_back(*w);
  }
  const std::uint32_t state = client.read_register(rm::kRegGyroState);
  EXPECT_EQ(rm::kGyroStateRunning.get(state), 1u);
  EXPECT_EQ(rm::kGyroStateAbsent.get(state), 0u);
  EXPECT_EQ(rm::kGyroStateFaults.get(state), 0u);
  EXPECT_TRUE(gyro.violations().empty()) << gyro.violations().front();

  // The windows partition the model's reads: window k holds the next gyro_count samples.
  const auto& reads = gyro.reads();
  std::size_t next = 0, running_from = windows.size();
  for (std::size_t k = 0; k < windows.size(); ++k) {
    const auto& w = windows[k];
    if (w.gyro_count == 0) {
      ASSERT_LT(k, 5u) << "a window without samples once running";
      EXPECT_NE(w.gyro_flags & (1u << rm::kGyroFlagNotRunning), 0u) << "window " << k;
      continue;
    }
    running_from = std::min(running_from, k);
    ASSERT_EQ(w.gyro_flags, 0u) << "window " << k;
    ASSERT_LE(next + w.gyro_count, reads.size())
        << "window " << k << " has samples the part never gave";
    std::int64_t sum = 0;
    for (std::size_t i = 0; i < w.gyro_count; ++i) sum += reads[next + i].value;
    ASSERT_EQ(w.gyro_sum, sum) << "window " << k << " (seed " << seed << ")";
    next += w.gyro_count;
  }
  ASSERT_LT(running_from, 5u);
  EXPECT_GE(next + 12, reads.size()) << "samples read but in no window";
  EXPECT_GE(next, (windows.size() - running_from) * 9);

  // The snapshot registers: the same window as SNAP_SEQ latched, sign-extended.
  const std::uint32_t seq = client.read_register(rm::kRegSnapSeq);
  const auto sum = static_cast<std::int32_t>(client.read_register(rm::kRegSnapGyroSum));
  const std::uint32_t g = client.read_register(rm::kRegSnapGyro);
  // ... equal to the streamed window of that sequence number (taken already, or buffered while
  // the reads ran).
  std::optional<omniloc::protocol::Window> same;
  if (windows.back().seq >= seq && seq > windows.front().seq)
    same = windows[seq - windows.front().seq];
  for (int i = 0; i < 20 && !same; ++i) {
    const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
    ASSERT_TRUE(w.has_value());
    if (w->seq == seq) same = w;
  }
  ASSERT_TRUE(same.has_value()) << "window " << seq << " was not streamed";
  EXPECT_EQ(sum, same->gyro_sum);
  EXPECT_EQ(rm::kSnapGyroCount.get(g), same->gyro_count);
  EXPECT_EQ(rm::kSnapGyroFlags.get(g), same->gyro_flags);
  EXPECT_GE(same->gyro_count, 9u);
  std::printf(
      "%zu windows, %zu samples summed exactly (seed %llu); snapshot window %u: sum %d LSB of %u "
      "samples\n",
      windows.size(), next, static_cast<unsigned long long>(seed), seq, sum,
      rm::kSnapGyroCount.get(g));

  // The part stops giving data-ready: a timeout (flag 1) within 5 ms, then the start-up again.
  gyro.faults().no_data_ready = true;
  bool timed_out = false;
  for (int i = 0; i < 20; ++i) {
    const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
    ASSERT_TRUE(w.has_value());
    timed_out |= (w->gyro_flags >> rm::kGyroFlagTimeout) & 1u;
  }
  EXPECT_TRUE(timed_out);
  EXPECT_EQ(rm::kStatusGyroFault.get(client.read_register(rm::kRegStatus)), 1u);
  gyro.faults().no_data_ready = false;
  client.write_register(rm::kRegStatus, rm::kStatusGyroFault.put(0, 1));
  for (int i = 0; i < 10; ++i) (void)client.poll_telemetry(std::chrono::milliseconds(100));
  const auto after = client.poll_telemetry(std::chrono::milliseconds(100));
  ASSERT_TRUE(after.has_value());
  EXPECT_EQ(after->gyro_flags, 0u) << "running again after the start-up";
  EXPECT_GE(after->gyro_count, 9u);
  EXPECT_GE(rm::kGyroStateFaults.get(client.read_register(rm::kRegGyroState)), 1u);
}

// With nothing on the gyro PMOD (MISO pulled up: WHO_AM_I reads 0xFF) the windows say ABSENT and
// NOT_RUNNING with no sample, GYRO_STATE.ABSENT is set and the red LED is on.
TEST(OmnilocTop, NoGyroFittedIsAbsentInEveryWindow) {
  BoardSim board;
  omniloc::sim::SimTransport transport(board);
  omniloc::BoardClient client(transport);
  client.write_register(rm::kRegControl, rm::kControlStream.put(rm::kControlEnable.put(0, 1), 1));
  std::vector<omniloc::protocol::Window> windows;
  while (windows.size() < 30) {
    const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
    ASSERT_TRUE(w.has_value());
    windows.push_back(*w);
  }
  for (std::size_t k = 2; k < windows.size(); ++k) {
    EXPECT_EQ(windows[k].gyro_count, 0u);
    EXPECT_NE(windows[k].gyro_flags & (1u << rm::kGyroFlagAbsent), 0u) << "window " << k;
    EXPECT_NE(windows[k].gyro_flags & (1u << rm::kGyroFlagNotRunning), 0u) << "window " << k;
  }
  const std::uint32_t state = client.read_register(rm::kRegGyroState);
  EXPECT_EQ(rm::kGyroStateAbsent.get(state), 1u);
  EXPECT_EQ(rm::kGyroStateRunning.get(state), 0u);
  EXPECT_GE(rm::kGyroStateFaults.get(state), 3u) << "a wrong WHO_AM_I every 101 ms";
  EXPECT_TRUE(board.error_led());
}

}  // namespace
