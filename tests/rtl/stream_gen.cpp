#include "stream_gen.hpp"

#include <algorithm>

namespace omniloc::rtl_tb {
namespace {

struct Builder {
  PinStream s;
  bool a = false;
  bool b = false;
  bool forward = true;
  std::uint64_t last_a = 0;
  std::uint64_t last_b = 0;

  void toggle_a(std::uint64_t t) {
    a = !a;
    s.a.push_back({t, a});
    last_a = t;
  }
  void toggle_b(std::uint64_t t) {
    b = !b;
    s.b.push_back({t, b});
    last_b = t;
  }
  // One quadrature step in the running direction: forward (A leads B) is AB 00,10,11,01.
  bool step_toggles_a() const { return forward ? (a == b) : (a != b); }
};

}  // namespace

PinStream generate_stream(std::mt19937_64& rng, const StreamProfile& p, std::uint64_t steps,
                          std::uint64_t start, unsigned filter_len,
                          const std::vector<std::uint64_t>& ticks) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::uint64_t hold = std::max(filter_len, 1u);
  auto rand_in = [&](std::uint64_t lo, std::uint64_t hi) {
    return std::uniform_int_distribution<std::uint64_t>(lo, std::max(lo, hi))(rng);
  };

  Builder g;
  g.a = (rng() & 1) != 0;
  g.b = (rng() & 1) != 0;
  g.s.a0 = g.a;
  g.s.b0 = g.b;
  g.last_a = g.last_b = start;
  std::uint64_t t = start + hold + 2;

  // Earliest edge a pin may change again so that its previous level still passes the filter.
  auto ready = [&](bool pin_a, std::uint64_t at) {
    return std::max(at, (pin_a ? g.last_a : g.last_b) + hold);
  };

  while (g.s.steps < steps) {
    const double r = u(rng);
    if (r < p.p_pause) {
      t += rand_in(1, p.max_pause);
    } else if (r < p.p_pause + p.p_bounce) {
      // Bounce: width around the filter length, so both sides of it occur.
      const bool on_a = (rng() & 1) != 0;
      const std::uint64_t width = rand_in(1, 2 * hold + 1);
      t = ready(on_a, t);
      if (on_a) {
        g.toggle_a(t);
        g.toggle_a(t + width);
      } else {
        g.toggle_b(t);
        g.toggle_b(t + width);
      }
      t += width + rand_in(p.min_gap, p.max_gap);
    } else if (r < p.p_pause + p.p_bounce + p.p_illegal) {
      t = std::max(ready(true, t), ready(false, t));
      g.toggle_a(t);
      g.toggle_b(t);
      t += rand_in(p.min_gap, p.max_gap);
    } else if (r < p.p_pause + p.p_bounce + p.p_illegal + p.p_boundary_reversal && !ticks.empty()) {
      // A step whose decoder pulse lands at tick - 1, tick or tick + 1, and its reversal
      // one filter length later: the pair straddles (or just touches) the window boundary.
      // Pin edge e shows as a pulse after edge e + hold + 2.
      const auto it = std::lower_bound(ticks.begin(), ticks.end(), t + 2 * hold + 8);
      if (it == ticks.end()) {
        t += 1;
        continue;
      }
      const std::uint64_t target = *it - hold - 2 + rand_in(0, 2) - 1;
      const bool on_a = g.step_toggles_a();
      const std::uint64_t e1 = ready(on_a, std::max(target, t));
      if (on_a)
        g.toggle_a(e1);
      else
        g.toggle_b(e1);
      const std::uint64_t e2 = e1 + hold + rand_in(0, 1);
      if (on_a)
        g.toggle_a(e2);
      else
        g.toggle_b(e2);
      g.forward = !g.forward;
      g.s.steps += 2;
      t = e2 + rand_in(p.min_gap, p.max_gap);
    } else {
      if (u(rng) < p.p_reverse) g.forward = !g.forward;
      const bool on_a = g.step_toggles_a();
      t = ready(on_a, t);
      if (on_a)
        g.toggle_a(t);
      else
        g.toggle_b(t);
      ++g.s.steps;
      t += rand_in(p.min_gap, p.max_gap);
    }
  }
  g.s.end_edge = t + 2 * hold;
  return g.s;
}

}  // namespace omniloc::rtl_tb
