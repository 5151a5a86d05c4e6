// Cycle-level quadrature A/B waveforms for the four motor encoders, streamed edge by edge from a
// World (no arrays: a 30 s run at 40 MHz is 1.2e9 cycles).
//
// Convention (matches rtl/quadrature_decoder.v): the quarter-step index q of an encoder gives the
// levels AB = 00, 10, 11, 01 for q mod 4 = 0, 1, 2, 3. Forward (q increasing, a positive wheel
// speed V_i of eq. (9), a positive count) means A leads B. The level for cycle c is that of
// floor(position(c)), the same position World::next_window counts from, so a decoder that counts
// every edge up to a window's end cycle reproduces the window's counts exactly.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>

#include "omniloc_sim/world.hpp"

namespace omniloc::sim {

struct QuadratureEdge {
  std::int64_t cycle = 0;  ///< first cycle at which the new levels hold
  int motor = 0;           ///< 0..3 (wheel motor+1)
  bool a = false;
  bool b = false;
};

/// A/B levels for a quarter-step index.
[[nodiscard]] constexpr bool level_a(std::int64_t quarter) {
  const std::int64_t p = quarter & 3;
  return p == 1 || p == 2;
}
[[nodiscard]] constexpr bool level_b(std::int64_t quarter) {
  return (quarter & 3) >= 2;
}

class QuadratureStream {
 public:
  /// Runs its own World; a second World with the same config and trajectory yields the same
  /// motion (everything is seeded), so its windows can be compared with this stream.
  QuadratureStream(const WorldConfig& config, Trajectory trajectory);

  /// The next level change at or before `limit_cycle` (any motor, earliest first; ties by motor),
  /// stepping the world as needed; nullopt if there is none up to the limit.
  /// Throws std::runtime_error if an encoder would move two quarter-steps in one cycle.
  std::optional<QuadratureEdge> next_edge(std::int64_t limit_cycle);

  /// Levels of every motor at `cycle` (monotonic calls): bit 2m is A and bit 2m+1 is B of motor m.
  std::uint8_t levels_at(std::int64_t cycle);

  /// Fills levels for cycles first_cycle, first_cycle + 1, ... (one byte each, as levels_at), for a
  /// testbench that consumes blocks; calls must move forward in time.
  void fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out);

  /// Current quarter-step index of a motor (after the edges handed out so far).
  [[nodiscard]] std::int64_t quarter(int motor) const {
    return quarter_[static_cast<std::size_t>(motor)];
  }
  [[nodiscard]] std::uint8_t levels() const;
  [[nodiscard]] const World& world() const { return world_; }

 private:
  void schedule(int motor, std::int64_t from_cycle);

  World world_;
  std::array<std::int64_t, 4> quarter_{};
  std::array<std::int64_t, 4> next_cycle_{};  // next edge cycle within the current span, or -1
  std::array<int, 4> next_dir_{};
  std::int64_t quiet_until_ = -1;  // no edge beyond those handed out up to this cycle
  std::uint8_t levels_ = 0;        // levels() as of quiet_until_
};

}  // namespace omniloc::sim
