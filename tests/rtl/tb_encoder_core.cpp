// Whole-core testbench: rtl/encoder_core.v through omniloc_sim::EncoderCoreHarness against the
// golden models (golden_encoder.hpp): four channels of random quadrature at different speeds,
// every window and the sum of windows checked, plus the register file seen from the bus.
// Built twice (tests/rtl/CMakeLists.txt): against the default core (4 channels) and, as
// tb_encoder_core_3ch with OMNILOC_TB_CHANNELS=3, against the core built with CHANNELS = 3, where
// channel 3's pins still carry a stream but every window, register and status bit of it must be 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <omniloc/regmap.hpp>
#include <omniloc_sim/encoder_core_harness.hpp>

#include "golden_encoder.hpp"
#include "stream_gen.hpp"
#include "tb_support.hpp"

namespace {

using omniloc::rtl_golden::Mode;
using omniloc::rtl_tb::StreamProfile;
using omniloc_sim::EncoderCoreHarness;
namespace rm = omniloc::regmap;

#ifndef OMNILOC_TB_CHANNELS
#define OMNILOC_TB_CHANNELS 4
#endif
// The channels the core under test was built with (its CHANNELS parameter).
constexpr int kBuiltChannels = OMNILOC_TB_CHANNELS;
static_assert(kBuiltChannels == 3 || kBuiltChannels == rm::kChannels);

constexpr std::uint64_t kDefaultPeriodCycles = 40'000'000 / 100;
// Reset is 2 cycles, so the first edge with rst_i low is edge 2 (harness cycle numbering).
constexpr std::uint64_t kFirstEdge = 2;
// tick_o shows after edge kFirstEdge + period - 1 first.
constexpr std::uint64_t kFirstTick = kFirstEdge + kDefaultPeriodCycles - 1;

struct StreamConfig {
  std::string name;
  unsigned filter_len = 0;
  Mode mode = Mode::kX4;
  std::uint32_t period_cycles = 2000;
  std::uint64_t steps_per_channel = 0;
  std::array<StreamProfile, 4> profiles{};
};

struct StreamReport {
  std::string failure;  // empty: passed
  std::uint64_t fail_cycle = 0;
  std::array<std::uint64_t, 4> steps{};
  std::array<std::uint64_t, 4> counted{};
  std::uint64_t windows = 0;
  std::uint64_t snapshots = 0;
  std::uint64_t relatched = 0;  // snapshots whose later reads saw a bank re-latched by a consume
  std::uint64_t cycles = 0;
};

// The snapshot reader: SNAP_SEQ (latches) then the rest of the bank, one read per cycle.
const std::vector<std::uint8_t> kSnapshotOrder = {
    rm::kRegSnapSeq,       rm::kRegSnapCount0,    rm::kRegSnapCount1,    rm::kRegSnapCount2,
    rm::kRegSnapCount3,    rm::kRegSnapPosition0, rm::kRegSnapPosition1, rm::kRegSnapPosition2,
    rm::kRegSnapPosition3, rm::kRegSnapDir,       rm::kRegSnapTimestamp};

StreamReport run_streams(const StreamConfig& cfg, std::uint64_t seed,
                         const omniloc::rtl_tb::TraceRequest* trace) {
  StreamReport rep;
  std::mt19937_64 rng(seed);
  EncoderCoreHarness h;
  auto fail = [&](const std::string& what) {
    if (rep.failure.empty()) {
      rep.failure = what;
      rep.fail_cycle = h.cycle();
    }
  };

  // Golden tick schedule: the first window keeps the reset period, then cfg.period_cycles.
  std::vector<std::uint64_t> ticks{kFirstTick};
  const std::uint64_t start = 40;
  std::array<omniloc::rtl_tb::PinStream, 4> streams;
  // Streams start after the first (long) window so every window boundary is a short-period one.
  const std::uint64_t stream_start = kFirstTick + 10;
  // Pre-compute ticks generously, generate streams, then trim.
  auto extend_ticks = [&](std::uint64_t until) {
    while (ticks.back() < until) ticks.push_back(ticks.back() + cfg.period_cycles);
  };
  extend_ticks(stream_start + cfg.steps_per_channel * 200 + 10'000);
  std::uint64_t end_edge = 0;
  for (int ch = 0; ch < 4; ++ch) {
    streams[ch] = omniloc::rtl_tb::generate_stream(rng, cfg.profiles[ch], cfg.steps_per_channel,
                                                   stream_start, cfg.filter_len, ticks);
    end_edge = std::max(end_edge, streams[ch].end_edge);
    rep.steps[ch] = streams[ch].steps;
  }
  const std::uint64_t horizon = end_edge + 8;
  ticks.erase(std::upper_bound(ticks.begin(), ticks.end(), horizon + cfg.period_cycles),
              ticks.end());
  while (ticks.back() < horizon + 16) ticks.push_back(ticks.back() + cfg.period_cycles);
  const std::uint64_t last_tick = ticks.back();

  std::array<std::vector<omniloc::rtl_golden::Window>, 4> golden;
  std::array<std::uint64_t, 4> golden_errors{};
  std::array<std::int64_t, 4> golden_total{};
  std::array<std::uint64_t, 4> first_error_window{};
  for (int ch = 0; ch < 4; ++ch) {
    const auto pulses = omniloc::rtl_golden::channel_pulses(
        streams[ch].a0, streams[ch].b0, streams[ch].a, streams[ch].b, cfg.filter_len, cfg.mode);
    golden[ch] = omniloc::rtl_golden::windows(pulses, ticks);
    // A channel the core was not built with counts nothing, whatever its pins do.
    if (ch >= kBuiltChannels)
      std::fill(golden[ch].begin(), golden[ch].end(), omniloc::rtl_golden::Window{});
    first_error_window[ch] = UINT64_MAX;
    for (std::size_t k = 0; k < golden[ch].size(); ++k) {
      golden_errors[ch] += golden[ch][k].errors;
      golden_total[ch] += golden[ch][k].count;
      if (golden[ch][k].errors != 0 && first_error_window[ch] == UINT64_MAX)
        first_error_window[ch] = k;
    }
    for (const auto& p : pulses) rep.counted[ch] += (p.delta != 0);
  }

  // Initial pin levels before reset ends; then configure the core.
  std::uint8_t a_mask = 0;
  std::uint8_t b_mask = 0;
  for (int ch = 0; ch < 4; ++ch) {
    a_mask |= static_cast<std::uint8_t>(streams[ch].a0 << ch);
    b_mask |= static_cast<std::uint8_t>(streams[ch].b0 << ch);
  }
  h.set_pins(a_mask, b_mask);
  if (trace != nullptr && trace->from_cycle == 0) h.open_trace(trace->path);
  const auto w1 = h.write(rm::kRegFilter, cfg.filter_len);
  const auto w2 = h.write(rm::kRegPeriod, cfg.period_cycles);
  const auto w3 = h.write(rm::kRegControl, 1u | (static_cast<unsigned>(cfg.mode) << 1));
  if (w1.err || w2.err || w3.err) fail("configuration write refused");
  if (h.cycle() >= start) fail("configuration took too long");

  std::array<std::size_t, 4> ia{};
  std::array<std::size_t, 4> ib{};
  std::size_t reader_pos = 0;
  bool reader_active = false;
  std::vector<std::uint32_t> snap;
  // The one frozen bank (docs/RTL.md): a SNAP_SEQ read or a consume strobe latches the last window
  // captured before that edge; every SNAP_* read answers from the bank as it stood before its own
  // edge. frozen_seq models it (0 = nothing latched yet); snap_frozen holds, per read of the
  // snapshot, the window it must describe.
  std::uint64_t live_seq = 0;  // windows captured at earlier edges
  std::uint64_t frozen_seq = 0;
  std::vector<std::uint64_t> snap_frozen;
  int acting_read = -1;  // the address read in the previous cycle, or -1
  int reader_wait = 0;   // cycles since the last read was issued
  std::uniform_int_distribution<int> reader_start(0, 199);
  std::uint64_t expected_seq = 1;
  bool consume_next = false;

  while (h.cycle() <= last_tick + 2 && rep.failure.empty()) {
    const std::uint64_t s = h.cycle();
    if (trace != nullptr && trace->from_cycle != 0 && s == trace->from_cycle)
      h.open_trace(trace->path);
    for (int ch = 0; ch < 4; ++ch) {
      const auto bit = static_cast<std::uint8_t>(1u << ch);
      while (ia[ch] < streams[ch].a.size() && streams[ch].a[ia[ch]].edge == s) {
        a_mask = streams[ch].a[ia[ch]].level ? (a_mask | bit) : (a_mask & ~bit);
        ++ia[ch];
      }
      while (ib[ch] < streams[ch].b.size() && streams[ch].b[ib[ch]].edge == s) {
        b_mask = streams[ch].b[ib[ch]].level ? (b_mask | bit) : (b_mask & ~bit);
        ++ib[ch];
      }
    }
    h.set_pins(a_mask, b_mask);
    const bool consume_now = consume_next;
    if (consume_now) h.consume_window();
    consume_next = false;
    // The snapshot reader issues one read per cycle.
    if (!reader_active && s > stream_start && reader_start(rng) == 0) {
      reader_active = true;
      reader_pos = 0;
      snap.clear();
      snap_frozen.clear();
    }
    bool latch = consume_now;
    // The read issued in the previous cycle takes effect at this edge (the bus is pipelined):
    // SNAP_SEQ answers the live SEQ and latches; the other SNAP_* answer the bank before this edge.
    if (acting_read >= 0) {
      const bool is_seq = acting_read == rm::kRegSnapSeq;
      snap_frozen.push_back(is_seq ? live_seq : frozen_seq);
      latch = latch || is_seq;
      acting_read = -1;
    }
    if (latch) frozen_seq = live_seq;
    if (reader_active && reader_pos < kSnapshotOrder.size()) {
      acting_read = kSnapshotOrder[reader_pos];
      h.issue_read(kSnapshotOrder[reader_pos++]);
      reader_wait = 0;
    }
    h.step();

    if (reader_active && reader_pos == kSnapshotOrder.size() &&
        ++reader_wait > EncoderCoreHarness::kBusLatency) {
      fail("snapshot read not acknowledged");
      break;
    }
    if (const auto r = h.response(); reader_active && r) {
      if (r->err) {
        fail("snapshot read refused");
        break;
      }
      snap.push_back(r->data);
      if (snap.size() == kSnapshotOrder.size()) {
        reader_active = false;
        ++rep.snapshots;
        const std::uint32_t seq = snap[0];
        if (seq != snap_frozen[0]) {
          fail("SNAP_SEQ " + std::to_string(seq) + ", golden " + std::to_string(snap_frozen[0]));
        }
        if (seq >= 1 && seq <= ticks.size()) {
          // Each read against the window the bank held at its edge (a consume strobe in the middle
          // of the sequence re-latches the bank, with STREAM on the link's TELEMETRY does that).
          auto window_of = [&](std::size_t i) -> std::size_t { return snap_frozen[i] - 1; };
          for (int ch = 0; ch < 4; ++ch) {
            const std::size_t kc = window_of(1 + ch), kp = window_of(5 + ch);
            if (snap_frozen[1 + ch] == 0 || snap_frozen[5 + ch] == 0 ||
                static_cast<std::int32_t>(snap[1 + ch]) != golden[ch][kc].count ||
                snap[5 + ch] != golden[ch][kp].position) {
              std::ostringstream os;
              os << "torn or wrong snapshot of window " << seq << " channel " << ch << ": count "
                 << static_cast<std::int32_t>(snap[1 + ch]) << " position " << snap[5 + ch]
                 << ", golden (windows " << snap_frozen[1 + ch] << ", " << snap_frozen[5 + ch]
                 << ") " << (snap_frozen[1 + ch] ? golden[ch][kc].count : 0) << " / "
                 << (snap_frozen[5 + ch] ? golden[ch][kp].position : 0u);
              fail(os.str());
            }
          }
          std::uint32_t dir = 0;
          const std::size_t kd = window_of(9);
          for (int ch = 0; ch < 4; ++ch) dir |= (golden[ch][kd].dir ? 1u : 0u) << ch;
          if (snap[9] != dir)
            fail("snapshot SNAP_DIR mismatch in window " + std::to_string(kd + 1));
          const std::size_t kt = window_of(10);
          if (snap[10] != static_cast<std::uint32_t>(ticks[kt] - 1)) {
            fail("snapshot SNAP_TIMESTAMP " + std::to_string(snap[10]) + " != golden " +
                 std::to_string(ticks[kt] - 1) + " in window " + std::to_string(kt + 1));
          }
          if (snap_frozen.back() != seq) ++rep.relatched;
        } else if (seq != 0) {
          fail("SNAP_SEQ out of range: " + std::to_string(seq));
        }
      }
    }

    if (h.tick() != std::binary_search(ticks.begin(), ticks.end(), s)) {
      fail("tick_o " + std::to_string(h.tick()) + " at edge " + std::to_string(s) +
           " disagrees with the golden schedule");
    }
    if (h.win_valid()) {
      const auto w = h.window();
      consume_next = true;
      if (w.seq != expected_seq) {
        fail("window sequence " + std::to_string(w.seq) + ", expected " +
             std::to_string(expected_seq));
        break;
      }
      const std::size_t k = expected_seq - 1;
      if (s != ticks[k] + 1)
        fail("win_valid_o at edge " + std::to_string(s) + ", golden " +
             std::to_string(ticks[k] + 1));
      if (w.timestamp != static_cast<std::uint32_t>(ticks[k] - 1))
        fail("window timestamp mismatch in window " + std::to_string(w.seq));
      std::uint8_t illegal_bits = 0;
      for (int ch = 0; ch < 4; ++ch) {
        const auto& gw = golden[ch][k];
        if (w.count[ch] != gw.count || w.position[ch] != gw.position ||
            ((w.dir >> ch) & 1) != (gw.dir ? 1 : 0)) {
          std::ostringstream os;
          os << "window " << w.seq << " channel " << ch << ": count " << w.count[ch] << " position "
             << w.position[ch] << " dir " << ((w.dir >> ch) & 1) << "; golden " << gw.count << " "
             << gw.position << " " << gw.dir;
          fail(os.str());
        }
        if (first_error_window[ch] <= k) illegal_bits |= static_cast<std::uint8_t>(1u << ch);
      }
      if (w.status != illegal_bits) {
        fail("window " + std::to_string(w.seq) + " status " + std::to_string(w.status) +
             ", golden " + std::to_string(illegal_bits) + " (sticky ILLEGAL bits, no OVERRUN)");
      }
      ++rep.windows;
      ++expected_seq;
      live_seq = w.seq;
    }
  }
  if (rep.failure.empty() && rep.windows != ticks.size()) {
    fail("saw " + std::to_string(rep.windows) + " windows, golden " + std::to_string(ticks.size()));
  }
  if (rep.failure.empty()) {
    for (int ch = 0; ch < 4; ++ch) {
      // ERROR_COUNTn saturates at 2^ERROR_COUNT_BITS - 1 (the hostile streams make thousands).
      const auto e = h.read(static_cast<std::uint8_t>(rm::kRegErrorCount0 + ch));
      const std::uint64_t saturated =
          std::min<std::uint64_t>(golden_errors[ch], (1u << rm::kErrorCountBits) - 1);
      if (e.err || e.data != saturated) {
        fail("ERROR_COUNT" + std::to_string(ch) + " = " + std::to_string(e.data) + ", golden " +
             std::to_string(golden_errors[ch]) + " saturated at " + std::to_string(saturated));
      }
      std::int64_t sum = 0;
      for (const auto& gw : golden[ch]) sum += gw.count;
      if (sum != golden_total[ch]) fail("golden sum inconsistent");
      // Sum of windows == final position (what the core reports in its last window).
      if (static_cast<std::uint32_t>(sum) != golden[ch].back().position)
        fail("golden position != sum");
    }
  }
  rep.cycles = h.cycle();
  return rep;
}

void run_and_check(const StreamConfig& cfg, std::uint64_t default_seed) {
  const std::uint64_t seed = omniloc::rtl_tb::test_seed(cfg.name, default_seed);
  const auto rep = run_streams(cfg, seed, nullptr);
  std::cout << "[" << cfg.name << "] cycles=" << rep.cycles << " windows=" << rep.windows
            << " snapshots=" << rep.snapshots << " re-latched mid-snapshot=" << rep.relatched
            << "\n";
  for (int ch = 0; ch < 4; ++ch) {
    std::cout << "  channel " << ch << ": steps=" << rep.steps[ch] << " counted=" << rep.counted[ch]
              << "\n";
  }
  if (!rep.failure.empty()) {
    omniloc::rtl_tb::TraceRequest tr{omniloc::rtl_tb::trace_path(cfg.name, seed),
                                     rep.fail_cycle > 3000 ? rep.fail_cycle - 3000 : 0};
    const auto again = run_streams(cfg, seed, &tr);
    FAIL() << cfg.name << " seed " << seed << " failed at cycle " << rep.fail_cycle << ": "
           << rep.failure << "\n  trace (cycles " << tr.from_cycle << ".." << again.fail_cycle
           << "): " << tr.path;
  }
  for (int ch = 0; ch < 4; ++ch) EXPECT_GE(rep.steps[ch], cfg.steps_per_channel);
}

// Profiles at filter length `hold`: the fastest legal rate alternates A and B one cycle apart.
StreamProfile fastest(unsigned hold) {
  StreamProfile p;
  p.min_gap = 1;
  p.max_gap = std::max(1u, hold);
  p.p_reverse = 0.02;
  return p;
}
StreamProfile medium() {
  StreamProfile p;
  p.min_gap = 2;
  p.max_gap = 12;
  p.p_reverse = 0.05;
  p.p_bounce = 0.05;
  return p;
}
StreamProfile stop_and_go() {
  StreamProfile p;
  p.min_gap = 1;
  p.max_gap = 4;
  p.p_reverse = 0.01;
  p.p_pause = 0.0005;
  p.max_pause = 5000;
  return p;
}
StreamProfile hostile() {
  StreamProfile p;
  p.min_gap = 1;
  p.max_gap = 6;
  p.p_reverse = 0.1;
  p.p_bounce = 0.1;
  p.p_illegal = 0.002;
  p.p_boundary_reversal = 0.01;
  return p;
}

TEST(EncoderCore, MillionEdgesPerChannelX4Filter3) {
  StreamConfig cfg;
  cfg.name = "core_x4_filter3";
  cfg.filter_len = 3;
  cfg.mode = Mode::kX4;
  cfg.period_cycles = 2000;
  cfg.steps_per_channel = 1'000'000;
  cfg.profiles = {fastest(3), medium(), stop_and_go(), hostile()};
  run_and_check(cfg, 20261122);
}

// Filter off: the fastest legal rate is one edge per clock on every channel.
TEST(EncoderCore, MillionEdgesPerChannelX4NoFilterOneEdgePerCycle) {
  StreamConfig cfg;
  cfg.name = "core_x4_nofilter_fastest";
  cfg.filter_len = 0;
  cfg.mode = Mode::kX4;
  cfg.period_cycles = 1000;
  cfg.steps_per_channel = 1'000'000;
  StreamProfile every_cycle = fastest(1);
  every_cycle.p_reverse = 0.05;
  StreamProfile reversals = every_cycle;
  reversals.p_boundary_reversal = 0.02;
  reversals.p_illegal = 0.001;
  cfg.profiles = {every_cycle, reversals, stop_and_go(), hostile()};
  cfg.profiles[2].max_pause = 2000;
  run_and_check(cfg, 555);
}

TEST(EncoderCore, X2AndX1NoFilter) {
  for (const Mode mode : {Mode::kX2, Mode::kX1}) {
    StreamConfig cfg;
    cfg.name = mode == Mode::kX2 ? "core_x2_nofilter" : "core_x1_nofilter";
    cfg.filter_len = 0;
    cfg.mode = mode;
    cfg.period_cycles = 500;
    cfg.steps_per_channel = 100'000;
    cfg.profiles = {fastest(1), medium(), stop_and_go(), hostile()};
    cfg.profiles[2].max_pause = 1500;
    run_and_check(cfg, 7 + static_cast<unsigned>(mode));
  }
}

TEST(EncoderCore, LongFilterBounces) {
  StreamConfig cfg;
  cfg.name = "core_x4_filter20";
  cfg.filter_len = 20;
  cfg.mode = Mode::kX4;
  cfg.period_cycles = 3000;
  cfg.steps_per_channel = 50'000;
  StreamProfile bouncy = hostile();
  bouncy.p_bounce = 0.3;
  cfg.profiles = {fastest(20), bouncy, stop_and_go(), hostile()};
  run_and_check(cfg, 99);
}

}  // namespace

namespace {

// One forward quadrature step on channel `ch` of a pin state (AB 00 -> 10 -> 11 -> 01).
void step_forward(std::uint8_t& a, std::uint8_t& b, int ch) {
  const auto bit = static_cast<std::uint8_t>(1u << ch);
  const bool av = a & bit;
  const bool bv = b & bit;
  if (av == bv)
    a ^= bit;
  else
    b ^= bit;
}

TEST(EncoderCore, RegistersFromTheBus) {
  EncoderCoreHarness h;
  EXPECT_EQ(h.read(rm::kRegId).data, rm::kIdValue);
  EXPECT_EQ(h.read(rm::kRegVersion).data, rm::kVersionValue);
  EXPECT_EQ(h.read(rm::kRegConfig).data, static_cast<std::uint32_t>(kBuiltChannels))
      << "CONFIG.CHANNELS";
  EXPECT_EQ(h.read(rm::kRegPeriod).data, kDefaultPeriodCycles);
  EXPECT_EQ(h.read(rm::kRegControl).data, 0u);
  // Unknown addresses, read-only registers and refused values: err, nothing changes.
  EXPECT_TRUE(h.read(0x07).err);
  EXPECT_TRUE(h.read(0xFF).err);
  EXPECT_TRUE(h.write(rm::kRegId, 1).err);
  EXPECT_TRUE(h.write(rm::kRegSnapCount0, 1).err);
  EXPECT_EQ(h.read(rm::kRegStatus).data, 0u) << "read-only writes are not BAD_WRITE";
  EXPECT_TRUE(h.write(rm::kRegControl, 0b111).err) << "DECODE = 3 is reserved";
  EXPECT_TRUE(h.write(rm::kRegControl, 0x11).err) << "bit 4 is reserved";
  EXPECT_TRUE(h.write(rm::kRegPeriod, rm::kPeriodMinCycles - 1).err);
  EXPECT_TRUE(h.write(rm::kRegFilter, 256).err);
  EXPECT_EQ(h.read(rm::kRegControl).data, 0u);
  EXPECT_EQ(h.read(rm::kRegPeriod).data, kDefaultPeriodCycles);
  EXPECT_EQ(h.read(rm::kRegFilter).data, 0u);
  EXPECT_EQ(h.read(rm::kRegStatus).data, 1u << 5) << "BAD_WRITE set";
  EXPECT_FALSE(h.write(rm::kRegStatus, 1u << 5).err);
  EXPECT_EQ(h.read(rm::kRegStatus).data, 0u) << "W1C";
  EXPECT_FALSE(h.write(rm::kRegPeriod, rm::kPeriodMinCycles).err);
  EXPECT_FALSE(h.write(rm::kRegControl, 0b1101).err);  // enable, X1, stream
  EXPECT_EQ(h.read(rm::kRegControl).data, 0b1101u);
  EXPECT_TRUE(h.stream_enabled());
  EXPECT_FALSE(h.write(rm::kRegFilter, 255).err);
  EXPECT_EQ(h.read(rm::kRegFilter).data, 255u);
  // TIMESTAMP counts cycles: two reads one cycle apart differ by one.
  // (Back to back on the pipelined bus: the answers come kBusLatency cycles later, in order.)
  h.issue_read(rm::kRegTimestamp);
  h.step();
  h.issue_read(rm::kRegTimestamp);
  for (int i = 2; i < EncoderCoreHarness::kBusLatency; ++i) {
    h.step();
    ASSERT_FALSE(h.response().has_value()) << "answer before the bus latency";
  }
  h.step();
  ASSERT_TRUE(h.response().has_value());
  const std::uint32_t t0 = h.response()->data;
  h.step();
  ASSERT_TRUE(h.response().has_value());
  EXPECT_EQ(h.response()->data, t0 + 1);
}

TEST(EncoderCore, NoCountWithoutEnableAndNoEdgeAtPowerUp) {
  // Pins high through reset and priming: no count and no illegal transition.
  EncoderCoreHarness h;
  std::uint8_t a = 0xF;
  std::uint8_t b = 0xF;
  h.set_pins(a, b);
  h.reset(2);
  h.step(20);
  ASSERT_FALSE(h.write(rm::kRegPeriod, 200).err);
  // Disabled: 1000 forward steps on every channel, then enable and 7 more steps.
  for (int i = 0; i < 1000; ++i) {
    for (int ch = 0; ch < 4; ++ch) step_forward(a, b, ch);
    h.set_pins(a, b);
    h.step(3);
  }
  ASSERT_FALSE(h.write(rm::kRegControl, 1).err);
  h.step(10);
  for (int i = 0; i < 7; ++i) {
    for (int ch = 0; ch < 4; ++ch) step_forward(a, b, ch);
    h.set_pins(a, b);
    h.step(3);
  }
  // Wait for a window after the steps (the first tick comes one reset period after reset).
  while (h.cycle() < kFirstTick + 2 * 200 + 10) h.step();
  const auto seq = h.read(rm::kRegSnapSeq);
  ASSERT_GE(seq.data, 1u);
  for (int ch = 0; ch < 4; ++ch) {
    // A channel the core was not built with moved with the others but counts nothing.
    const std::uint32_t expected = ch < kBuiltChannels ? 7u : 0u;
    EXPECT_EQ(h.read(static_cast<std::uint8_t>(rm::kRegSnapPosition0 + ch)).data, expected)
        << "channel " << ch;
    EXPECT_EQ(h.read(static_cast<std::uint8_t>(rm::kRegErrorCount0 + ch)).data, 0u)
        << "channel " << ch;
  }
  EXPECT_EQ(h.read(rm::kRegStatus).data & 0xFu, 0u);
}

TEST(EncoderCore, OverrunWhenAWindowIsNotConsumed) {
  EncoderCoreHarness h;
  ASSERT_FALSE(h.write(rm::kRegPeriod, 100).err);
  ASSERT_FALSE(h.write(rm::kRegControl, 1).err);
  // First capture after the reset period, then 100-cycle windows.
  h.step(kDefaultPeriodCycles + 50);
  EXPECT_EQ(h.read(rm::kRegStatus).data & 0x10u, 0u) << "one window pending is not an overrun";
  h.step(100);
  EXPECT_EQ(h.read(rm::kRegStatus).data & 0x10u, 0x10u) << "second capture with the first unread";
  // Take the pending window, then clear the flag.
  h.consume_window();
  h.step();
  ASSERT_FALSE(h.write(rm::kRegStatus, 0x10).err);
  // Consuming every window (strobe after win_valid) keeps OVERRUN clear.
  for (int i = 0; i < 2000; ++i) {
    const bool v = h.win_valid();
    if (v) h.consume_window();
    h.step();
  }
  EXPECT_EQ(h.read(rm::kRegStatus).data & 0x10u, 0u);
  // So does reading SNAP_SEQ once per window.
  for (int i = 0; i < 20; ++i) {
    h.step(60);
    ASSERT_FALSE(h.read(rm::kRegSnapSeq).err);
    h.step(40 - EncoderCoreHarness::kBusLatency);  // 100 cycles a round, one read per window
  }
  EXPECT_EQ(h.read(rm::kRegStatus).data & 0x10u, 0u);
}

TEST(EncoderCore, TickExactAtDefaultsOver5Windows) {
  EncoderCoreHarness h;
  ASSERT_FALSE(h.write(rm::kRegControl, 1).err);
  std::uint64_t last = 0;
  std::uint32_t last_ts = 0;
  int windows = 0;
  while (windows < 5) {
    h.step();
    if (h.tick()) {
      const std::uint64_t e = h.cycle() - 1;
      if (windows == 0) {
        EXPECT_EQ(e, kFirstTick);
      } else {
        EXPECT_EQ(e - last, kDefaultPeriodCycles);
      }
      last = e;
    }
    if (h.win_valid()) {
      const auto w = h.window();
      if (windows > 0) {
        EXPECT_EQ(w.timestamp - last_ts, kDefaultPeriodCycles);
      }
      last_ts = w.timestamp;
      EXPECT_EQ(w.seq, static_cast<std::uint32_t>(windows + 1));
      h.consume_window();
      ++windows;
    }
  }
}

}  // namespace
