#include "omniloc_sim/encoder_waveform.hpp"

#include <stdexcept>
#include <string>

namespace omniloc::sim {
namespace {

constexpr std::int64_t kOne = std::int64_t{1} << kFracBits;

// ceil(a / b) for b > 0.
std::int64_t ceil_div(std::int64_t a, std::int64_t b) {
  return -floor_div(-a, b);
}

}  // namespace

QuadratureStream::QuadratureStream(const WorldConfig& config, Trajectory trajectory)
    : world_(config, std::move(trajectory)) {
  for (int m = 0; m < 4; ++m) {
    quarter_[static_cast<std::size_t>(m)] =
        quarter_of(world_.last_step().end_pos[static_cast<std::size_t>(m)]);
    next_cycle_[static_cast<std::size_t>(m)] = -1;
  }
  levels_ = levels();
}

std::uint8_t QuadratureStream::levels() const {
  std::uint8_t v = 0;
  for (int m = 0; m < 4; ++m) {
    const std::int64_t q = quarter_[static_cast<std::size_t>(m)];
    v = static_cast<std::uint8_t>(v | (level_a(q) ? 1u << (2 * m) : 0u) |
                                  (level_b(q) ? 1u << (2 * m + 1) : 0u));
  }
  return v;
}

// Finds the first cycle after `from_cycle` in the current span at which the motor's floored
// position leaves its current quarter. With p(k) = p0 + floor(D k / n) (k cycles into the span):
// up:   p(k) >= (q+1) * ONE  <=>  D k >= T n  with T = (q+1) ONE - p0   -> k = ceil(T n / D)
// down: p(k) <  q * ONE      <=>  D k <  U n  with U = q ONE - p0      -> k = floor(U n / D) + 1
void QuadratureStream::schedule(int motor, std::int64_t from_cycle) {
  const auto i = static_cast<std::size_t>(motor);
  const StepSpan& s = world_.last_step();
  const std::int64_t n = s.end_cycle - s.begin_cycle;
  const std::int64_t d = s.end_pos[i] - s.begin_pos[i];
  const std::int64_t q = quarter_[i];
  std::int64_t k = -1;
  if (d > 0) {
    k = ceil_div(((q + 1) * kOne - s.begin_pos[i]) * n, d);
    next_dir_[i] = 1;
  } else if (d < 0) {
    const std::int64_t u = q * kOne - s.begin_pos[i];
    k = floor_div(-u * n, -d) + 1;  // floor(U n / D) with D < 0
    next_dir_[i] = -1;
  }
  // k >= 1 always: the span starts at the quarter the previous span ended in.
  const std::int64_t c = s.begin_cycle + k;
  next_cycle_[i] = (k >= 0 && c > from_cycle && c <= s.end_cycle) ? c : -1;
}

std::optional<QuadratureEdge> QuadratureStream::next_edge(std::int64_t limit_cycle) {
  for (;;) {
    int best = -1;
    for (int m = 0; m < 4; ++m) {
      const std::int64_t c = next_cycle_[static_cast<std::size_t>(m)];
      if (c >= 0 && (best < 0 || c < next_cycle_[static_cast<std::size_t>(best)])) best = m;
    }
    if (best >= 0) {
      const auto i = static_cast<std::size_t>(best);
      const std::int64_t c = next_cycle_[i];
      if (c > limit_cycle) {
        quiet_until_ = c - 1;
        levels_ = levels();
        return std::nullopt;
      }
      quarter_[i] += next_dir_[i];
      // The floored position at this cycle must be exactly the new quarter, or the encoder
      // jumped two states in one cycle (which no decoder can follow).
      if (quarter_of(position_at(world_.last_step(), best, c)) != quarter_[i])
        throw std::runtime_error("QuadratureStream: motor " + std::to_string(best) +
                                 " moves more than one quarter-step in cycle " + std::to_string(c));
      schedule(best, c);
      return QuadratureEdge{c, best, level_a(quarter_[i]), level_b(quarter_[i])};
    }
    if (world_.cycle() >= limit_cycle) {
      quiet_until_ = world_.cycle();
      levels_ = levels();
      return std::nullopt;
    }
    world_.step();
    for (int m = 0; m < 4; ++m) schedule(m, world_.last_step().begin_cycle);
  }
}

void QuadratureStream::fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out) {
  std::int64_t c = first_cycle;
  for (std::uint8_t& v : out) v = levels_at(c++);
}

std::uint8_t QuadratureStream::levels_at(std::int64_t cycle) {
  // Per-cycle callers mostly ask about cycles already known to be quiet.
  if (cycle <= quiet_until_) return levels_;
  while (next_edge(cycle)) {
  }
  return levels_;  // next_edge set it when it found no more edges up to `cycle`
}

}  // namespace omniloc::sim
