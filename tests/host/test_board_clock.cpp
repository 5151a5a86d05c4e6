// BoardClockModel (board_clock.hpp) against hand-made window sequences whose true host times are
// known: a 50 ppm crystal, USB latency exponential 0..2 ms, 20 ms late bursts, a long burst, a
// reconnect with a queue of stale windows, a board reset. The first-window anchoring the daemon had
// before is scored beside it on the same sequence.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "omniloc/detail/board_clock.hpp"
#include "omniloc_sim/sim_clocks.hpp"

namespace omniloc {
namespace {

struct Window {
  double board_ms, arrival_ms, true_host_ms;
};

// Windows every 10 ms of board time for `seconds`, on `crystal`, arrivals from `usb`.
std::vector<Window> drive(const sim::BoardCrystal& crystal, sim::UsbArrivals& usb,
                          double host_from_ms, double seconds) {
  std::vector<Window> out;
  const double b0 = std::ceil(crystal.board_ms(host_from_ms) / 10.0) * 10.0;
  for (double b = b0; crystal.host_ms(b) < host_from_ms + seconds * 1000.0; b += 10.0) {
    const double h = crystal.host_ms(b);
    out.push_back({b, usb.arrival_ms(h), h});
  }
  return out;
}

sim::SimClockConfig usb_config(double burst_every_s) {
  sim::SimClockConfig c;
  c.usb_jitter_mean_ms = 0.5;
  c.usb_jitter_max_ms = 2.0;
  c.burst_every_s = burst_every_s;
  c.burst_extra_ms = 20.0;
  c.burst_length_ms = 100.0;
  return c;
}

std::uint64_t seed_for(const char* name) {
  const std::uint64_t seed = std::random_device{}();
  std::printf("%s seed %llu\n", name, static_cast<unsigned long long>(seed));
  return seed;
}

TEST(BoardClock, FiftyPpmWithJitterAndBurstsStaysWithinPointThreeMsOfTruth) {
  const std::uint64_t seed = seed_for("FiftyPpm");
  for (const double ppm : {50.0, -50.0}) {
    const sim::BoardCrystal crystal{ppm, 123'456.0};
    sim::UsbArrivals usb(usb_config(5.0), seed);
    const auto ws = drive(crystal, usb, 0.0, 600.0);
    BoardClockModel model;
    const double anchor =
        ws.front().arrival_ms - ws.front().board_ms;  // the daemon before issue 18
    double max_err = 0.0, max_anchor_err = 0.0, max_in_burst = 0.0;
    int within_sigma3 = 0, scored = 0;
    for (const Window& w : ws) {
      const BoardClockEstimate e = model.add(w.board_ms, w.arrival_ms);
      EXPECT_LE(e.host_ms, w.arrival_ms);
      if (w.true_host_ms < 10'000.0) continue;  // converging
      const double err = std::abs(e.host_ms - w.true_host_ms);
      max_err = std::max(max_err, err);
      if (w.arrival_ms - w.true_host_ms > 15.0) max_in_burst = std::max(max_in_burst, err);
      max_anchor_err = std::max(max_anchor_err, std::abs(w.board_ms + anchor - w.true_host_ms));
      ++scored;
      within_sigma3 += err <= 3.0 * e.uncertainty_ms;
      EXPECT_TRUE(e.converged);
    }
    std::printf(
        "%+.0f ppm over 600 s: model max error %.4f ms (in bursts %.4f), drift %+.2f ppm, unc %.3f "
        "ms; "
        "first-window anchor max error %.2f ms\n",
        ppm, max_err, max_in_burst, model.last().drift_ppm, model.last().uncertainty_ms,
        max_anchor_err);
    EXPECT_LT(max_err, 0.3);
    EXPECT_LT(max_in_burst, 0.3);  // the bursts do not pull the line
    // host = board (1 - ppm) + ...: the model's drift is the host's rate against the board's.
    EXPECT_NEAR(model.last().drift_ppm, -ppm / (1.0 + ppm * 1e-6), 1.0);
    EXPECT_GT(max_anchor_err,
              25.0);  // 50 ppm over 10 minutes: 30 ms, which the anchor never corrects
    EXPECT_GE(within_sigma3, scored * 99 / 100) << "the stated uncertainty is honest";
    EXPECT_EQ(model.resets(), 0u);
  }
}

TEST(BoardClock, ALongBurstSpoilingThreeBucketsDoesNotMoveTheLine) {
  const std::uint64_t seed = seed_for("LongBurst");
  const sim::BoardCrystal crystal{50.0, 0.0};
  sim::UsbArrivals usb(usb_config(0.0), seed);
  auto ws = drive(crystal, usb, 0.0, 120.0);
  for (Window& w : ws)
    if (w.true_host_ms > 60'000.0 && w.true_host_ms < 63'500.0) w.arrival_ms += 20.0;  // 3.5 s late
  BoardClockModel model;
  double max_err = 0.0;
  for (const Window& w : ws) {
    const BoardClockEstimate e = model.add(w.board_ms, w.arrival_ms);
    if (w.true_host_ms > 10'000.0)
      max_err = std::max(max_err, std::abs(e.host_ms - w.true_host_ms));
  }
  std::printf("3.5 s burst of 20 ms: max error %.4f ms\n", max_err);
  EXPECT_LT(max_err, 0.3);
}

TEST(BoardClock, AReconnectWithAStaleQueueKeepsTheLine) {
  const std::uint64_t seed = seed_for("Reconnect");
  const sim::BoardCrystal crystal{50.0, 5'000.0};
  sim::UsbArrivals usb(usb_config(7.0), seed);
  const auto ws = drive(crystal, usb, 0.0, 90.0);
  BoardClockModel model;
  double max_err = 0.0;
  // Link down from 40 s to 42 s; the 100 windows of its last second wait and are read at once at 42
  // s.
  for (const Window& w : ws) {
    double arrival = w.arrival_ms;
    if (w.true_host_ms >= 40'000.0 && w.true_host_ms < 41'000.0) continue;  // lost with the link
    if (w.true_host_ms >= 41'000.0 && w.true_host_ms < 42'000.0) arrival = 42'000.5;
    const BoardClockEstimate e = model.add(w.board_ms, std::max(arrival, w.arrival_ms));
    if (w.true_host_ms > 10'000.0)
      max_err = std::max(max_err, std::abs(e.host_ms - w.true_host_ms));
  }
  std::printf("reconnect with a 1 s stale queue: max error %.4f ms, resets %llu\n", max_err,
              static_cast<unsigned long long>(model.resets()));
  EXPECT_LT(max_err, 0.3);
  EXPECT_EQ(model.resets(), 0u);
}

TEST(BoardClock, ABoardResetIsDetectedAndReanchored) {
  const std::uint64_t seed = seed_for("Reset");
  // The first run's board time covers 10 .. 70 s. After the restart it starts at: 0 (time went
  // back), 71 s (above the last one, but the windows arrive 1 s "late": the hold path), 200 s (far
  // ahead: arrivals below the line, which latency cannot explain).
  for (const double restart_board_ms : {0.0, 71'000.0, 200'000.0}) {
    sim::UsbArrivals usb(usb_config(7.0), seed);
    auto ws = drive(sim::BoardCrystal{50.0, 10'000.0}, usb, 0.0, 60.0);
    const double restart_host_ms = 62'000.0;  // 2 s unplugged
    const sim::BoardCrystal second{50.0, restart_board_ms - restart_host_ms * (1.0 + 50e-6)};
    const auto more = drive(second, usb, restart_host_ms, 60.0);
    ws.insert(ws.end(), more.begin(), more.end());
    BoardClockModel model;
    double max_err = 0.0, max_err_settled = 0.0;
    for (const Window& w : ws) {
      const BoardClockEstimate e = model.add(w.board_ms, w.arrival_ms);
      const double err = std::abs(e.host_ms - w.true_host_ms);
      if (w.true_host_ms > restart_host_ms + 2'000.0 && w.true_host_ms < restart_host_ms + 10'000.0)
        max_err = std::max(max_err, err);
      if (w.true_host_ms > restart_host_ms + 10'000.0)
        max_err_settled = std::max(max_err_settled, err);
    }
    std::printf(
        "reset, board time from %.0f ms: resets %llu, error 2-10 s after %.4f ms, after 10 s %.4f "
        "ms\n",
        restart_board_ms, static_cast<unsigned long long>(model.resets()), max_err,
        max_err_settled);
    EXPECT_EQ(model.resets(), 1u);
    EXPECT_LT(max_err, 2.5);
    EXPECT_LT(max_err_settled, 0.3);
  }
}

TEST(BoardClock, BoardTimeContinuesThroughAReconnectButNotThroughAReset) {
  // 40 MHz: the 32-bit counter wraps every 107.37 s. The last window before the link went down was
  // at raw 4'000'000'000 (board 50 s on the daemon's scale), arriving at host 1'000 ms.
  const double hz = 40e6;
  const BoardTimeMark last{4'000'000'000u, 50'000.0, 1'000.0, hz};
  const auto cycles_after = [&](double ms) {
    return static_cast<std::uint32_t>(
        (4'000'000'000ull + static_cast<std::uint64_t>(ms * hz / 1000.0)) & 0xFFFFFFFFu);
  };
  // Back after 2 s (the counter wrapped once meanwhile), the window arriving 3 ms late.
  auto b = continued_board_ms(last, cycles_after(2'000.0), hz, 1'000.0 + 2'003.0);
  ASSERT_TRUE(b.has_value());
  EXPECT_NEAR(*b, 52'000.0, 1e-6);
  // Back after 250 s (two more wraps), the crystal 50 ppm fast.
  b = continued_board_ms(last, cycles_after(250'000.0 * (1.0 + 50e-6)), hz, 1'000.0 + 250'000.0);
  ASSERT_TRUE(b.has_value());
  EXPECT_NEAR(*b, 50'000.0 + 250'012.5, 1e-3);
  // The board restarted while away: its counter is at 1.5 s after 4 s of host time.
  EXPECT_FALSE(
      continued_board_ms(last, static_cast<std::uint32_t>(1.5 * hz), hz, 5'000.0).has_value());
  // Another board (another clock).
  EXPECT_FALSE(continued_board_ms(last, cycles_after(2'000.0), 12e6, 3'000.0).has_value());
  // And the model: restart() starts a new epoch at the next window.
  BoardClockModel m;
  (void)m.add(0.0, 1.0);
  (void)m.add(10.0, 11.0);
  m.restart();
  EXPECT_EQ(m.add(20.0, 500.0).epoch, 2u);
  EXPECT_EQ(m.resets(), 1u);
}

TEST(BoardClock, BadConfigNamesTheField) {
  BoardClockConfig c;
  c.bucket_ms = 0.0;
  try {
    BoardClockModel m(c);
    FAIL() << "accepted bucket_ms 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bucket_ms"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace omniloc
