// Random quadrature pin streams for the encoder testbenches: steps at up to the fastest rate the
// filter lets through, reversals (also placed right at window boundaries), bounces shorter and
// longer than the filter, illegal jumps (A and B in the same sample) and stop-and-go pauses.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "golden_encoder.hpp"

namespace omniloc::rtl_tb {

struct StreamProfile {
  std::uint64_t min_gap = 1;  // cycles between changes of different pins (>= 1)
  std::uint64_t max_gap = 1;
  double p_reverse = 0.0;  // a step reverses the running direction
  double p_bounce = 0.0;   // a pin toggles and returns (width below or above the filter)
  double p_illegal = 0.0;  // A and B change together
  double p_pause = 0.0;    // stop for up to max_pause cycles
  std::uint64_t max_pause = 0;
  double p_boundary_reversal = 0.0;  // step + reversal whose pulses straddle a window boundary
};

struct PinStream {
  bool a0 = false;
  bool b0 = false;
  std::vector<rtl_golden::Change> a;
  std::vector<rtl_golden::Change> b;
  std::uint64_t steps = 0;  // quadrature steps generated (each a pin edge)
  std::uint64_t end_edge = 0;
};

/// Generate `steps` quadrature steps starting at edge `start`. `ticks` are the edges after which
/// tick_o shows (for boundary reversals); `filter_len` is the FILTER value in use.
PinStream generate_stream(std::mt19937_64& rng, const StreamProfile& profile, std::uint64_t steps,
                          std::uint64_t start, unsigned filter_len,
                          const std::vector<std::uint64_t>& ticks);

}  // namespace omniloc::rtl_tb
