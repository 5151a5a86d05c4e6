// The golden model the board's windows are checked against: an x4 quadrature decoder run over the
// very pin levels the board is given. It sits between the world simulator's quadrature stream and
// the board (an EncoderSource), and keeps the cumulative counts at the cycles around each window
// boundary (within kBand cycles of a multiple of the window period), so it can run for any length
// of time in constant memory.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <span>

#include "omniloc/robot_config.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::tb {

class GoldenQuadrature final : public omniloc::sim::EncoderSource {
 public:
  static constexpr std::int64_t kBand = 64;

  GoldenQuadrature(omniloc::sim::QuadratureStream& stream, std::int64_t window_cycles)
      : stream_(stream), period_(window_cycles) {}

  void fill_levels(std::int64_t first_cycle, std::span<std::uint8_t> out) override {
    stream_.fill_levels(first_cycle, out);
    std::lock_guard lock(mutex_);
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
      const std::int64_t cycle = first_cycle + static_cast<std::int64_t>(i);
      const std::int64_t r = cycle % period_;
      if (r <= kBand || r >= period_ - kBand) at_boundary_[cycle] = count_;
    }
    // Forget boundaries long past.
    while (!at_boundary_.empty() && at_boundary_.begin()->first < first_cycle - 200 * period_) {
      at_boundary_.erase(at_boundary_.begin());
    }
  }

  /// Cumulative counts at `cycle`, if it lies in a recorded band around a window boundary.
  [[nodiscard]] std::optional<std::array<std::int64_t, 4>> counts_at(std::int64_t cycle) const {
    std::lock_guard lock(mutex_);
    const auto it = at_boundary_.find(cycle);
    if (it == at_boundary_.end()) return std::nullopt;
    return it->second;
  }
  [[nodiscard]] int illegal() const {
    std::lock_guard lock(mutex_);
    return illegal_;
  }

 private:
  omniloc::sim::QuadratureStream& stream_;
  std::int64_t period_;
  mutable std::mutex mutex_;
  std::map<std::int64_t, std::array<std::int64_t, 4>> at_boundary_;
  std::array<std::int64_t, 4> count_{};
  std::array<int, 4> phase_{};
  int illegal_ = 0;
};

/// A noise-free world whose time base is the simulated board's clock (12 MHz, 10 ms windows), with
/// the encoders starting at AB = 00 as the board's decoders do after reset.
inline omniloc::sim::WorldConfig board_world(std::uint64_t seed) {
  using omniloc::sim::BoardSim;
  auto robot = omniloc::load_named_robot_config("default");
  auto config = omniloc::sim::WorldConfig::noise_free(robot, seed);
  config.set_clock(static_cast<double>(BoardSim::kClockHz));
  config.random_encoder_phase = false;
  return config;
}

}  // namespace omniloc::tb
