// Cycle-level quadrature waveforms: the streamed edges against a per-cycle evaluation of the
// encoder position, and window counts from an independent edge-counting decoder (the rule of
// rtl/quadrature_decoder.v) against World's per-window counts.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "omniloc_sim/encoder_waveform.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::sim {
namespace {

// Phase index g = {B, A^B}: 0,1,2,3 for AB = 00,10,11,01 (as the RTL decoder computes it).
int phase(bool a, bool b) {
  return (b ? 2 : 0) | ((a != b) ? 1 : 0);
}

// An edge counter written from the RTL's description, not from decoded_count().
struct Decoder {
  int mode = 4;
  int prev_g = 0;
  long long count = 0;
  void apply(bool a, bool b) {
    const int g = phase(a, b);
    const int step = (g - prev_g) & 3;
    ASSERT_NE(step, 2) << "illegal transition";
    if (step == 0) return;
    const bool forward = step == 1;
    const int low = forward ? prev_g : g;
    const bool selected = mode == 1 ? low == 0 : mode == 2 ? (low & 1) == 0 : true;
    if (selected) count += forward ? 1 : -1;
    prev_g = g;
  }
};

TEST(QuadratureStream, EdgesMatchPerCycleEvaluation) {
  WorldConfig cfg = WorldConfig::default_noise(RobotConfig{}, 17);
  cfg.slips.push_back({2, 0.05, 0.05, 40.0});
  QuadratureStream stream(cfg, make_trajectory("random_walk", 3));
  World ref(cfg, make_trajectory("random_walk", 3));
  const std::int64_t end = 16'000'000;  // 0.4 s at 40 MHz, through the start-up acceleration
  std::uint8_t expect_levels = 0;
  long long edges = 0;
  for (std::int64_t c = 1; c <= end; ++c) {
    if (c > ref.cycle()) ref.step();
    expect_levels = 0;
    for (int m = 0; m < 4; ++m) {
      const std::int64_t q = quarter_of(position_at(ref.last_step(), m, c));
      expect_levels = static_cast<std::uint8_t>(expect_levels | (level_a(q) << (2 * m)) |
                                                (level_b(q) << (2 * m + 1)));
    }
    const std::uint8_t before = stream.levels();
    const std::uint8_t got = stream.levels_at(c);
    if (got != before) ++edges;
    ASSERT_EQ(got, expect_levels) << "cycle " << c;
  }
  std::printf("%lld cycles with edges in 0.4 s\n", edges);
  EXPECT_GT(edges, 1000);
}

TEST(QuadratureStream, ForwardMeansALeadsB) {
  // Straight forward at yaw 0: wheels 3 and 4 turn forward (+sin 45), 1 and 2 backward.
  QuadratureStream s(WorldConfig::noise_free(RobotConfig{}, 1), make_trajectory("straight"));
  std::vector<int> g3;
  std::vector<int> g1;
  while (g3.size() < 9 || g1.size() < 9) {
    const auto e = s.next_edge(400'000'000);
    ASSERT_TRUE(e.has_value());
    if (e->motor == 2) g3.push_back(phase(e->a, e->b));
    if (e->motor == 0) g1.push_back(phase(e->a, e->b));
  }
  for (std::size_t i = 1; i < 9; ++i) {
    EXPECT_EQ((g3[i] - g3[i - 1]) & 3, 1);  // 00 -> 10 -> 11 -> 01: A leads
    EXPECT_EQ((g1[i] - g1[i - 1]) & 3, 3);  // reverse: B leads
  }
}

void compare_windows(int decoding, const char* trajectory, std::int64_t first_window_end) {
  RobotConfig r;
  r.decoding = decoding;
  WorldConfig cfg = WorldConfig::default_noise(r, 23);
  cfg.first_window_end_cycles = first_window_end;
  cfg.slips.push_back({4, 1.0, 0.4, 35.0});
  World world(cfg, make_trajectory(trajectory, 5));
  QuadratureStream stream(cfg, make_trajectory(trajectory, 5));
  std::array<Decoder, 4> dec;
  for (int m = 0; m < 4; ++m) {
    dec[static_cast<std::size_t>(m)].mode = decoding;
    const std::uint8_t lv = stream.levels();
    dec[static_cast<std::size_t>(m)].prev_g = phase(lv >> (2 * m) & 1, lv >> (2 * m + 1) & 1);
  }
  int windows = 0;
  while (!world.finished()) {
    const SimWindow sw = world.next_window();
    std::array<long long, 4> before{};
    for (std::size_t m = 0; m < 4; ++m) before[m] = dec[m].count;
    while (const auto e = stream.next_edge(sw.t_end_cycles))
      dec[static_cast<std::size_t>(e->motor)].apply(e->a, e->b);
    for (std::size_t m = 0; m < 4; ++m)
      ASSERT_EQ(dec[m].count - before[m], sw.window.counts[m])
          << "window " << sw.window.seq << " motor " << m;
    ++windows;
  }
  EXPECT_GT(windows, 300);
}

TEST(QuadratureStream, EdgeCountsEqualWindowCountsX4) {
  compare_windows(4, "figure_eight", 400'000);
}
TEST(QuadratureStream, EdgeCountsEqualWindowCountsX2OffsetWindows) {
  compare_windows(2, "boundary_tour", 123'457);
}
TEST(QuadratureStream, EdgeCountsEqualWindowCountsX1) {
  compare_windows(1, "straight", 400'000);
}

TEST(QuadratureStream, BlockFillEqualsPerCycleLevels) {
  const WorldConfig cfg = WorldConfig::default_noise(RobotConfig{}, 31);
  QuadratureStream a(cfg, make_trajectory("circle"));
  QuadratureStream b(cfg, make_trajectory("circle"));
  std::vector<std::uint8_t> block(50'000);
  int changes = 0;
  for (std::int64_t start = 1; start < 4'000'001;
       start += static_cast<std::int64_t>(block.size())) {
    a.fill_levels(start, block);
    for (std::size_t k = 0; k < block.size(); ++k) {
      const std::uint8_t v = b.levels_at(start + static_cast<std::int64_t>(k));
      ASSERT_EQ(block[k], v);
      changes += k > 0 && block[k] != block[k - 1];
    }
  }
  EXPECT_GT(changes, 100);
}

// Edges drained with next_edge() up to a limit, then levels_at() a little later: the cached levels
// must include every edge handed out.
TEST(QuadratureStream, MixingNextEdgeAndLevelsAt) {
  const WorldConfig cfg = WorldConfig::default_noise(RobotConfig{}, 41);
  QuadratureStream mixed(cfg, make_trajectory("random_walk", 41));
  QuadratureStream ref(cfg, make_trajectory("random_walk", 41));
  int edges = 0;
  for (std::int64_t limit = 1000; limit < 8'000'000; limit += 1000) {
    while (mixed.next_edge(limit)) ++edges;
    ASSERT_EQ(mixed.levels_at(limit + 13), ref.levels_at(limit + 13)) << "cycle " << limit + 13;
  }
  EXPECT_GT(edges, 1000);
}

TEST(QuadratureStream, ImpossiblySpeedyEncoderIsReported) {
  WorldConfig cfg = WorldConfig::noise_free(RobotConfig{}, 1);
  cfg.slips.push_back({1, 0.0, 1.0, 1.0e5});  // > 1 quarter-step per cycle at 40 MHz
  QuadratureStream s(cfg, make_trajectory("straight"));
  EXPECT_THROW((void)s.levels_at(100'000), std::runtime_error);
}

}  // namespace
}  // namespace omniloc::sim
