// Wrap-safe reconstruction of the board's 32-bit counters into 64-bit host values.
#include <stdexcept>
#include <string>

#include "omniloc/protocol.hpp"

namespace omniloc::protocol {

std::int64_t PositionUnwrapper::update(std::uint32_t raw_counts) {
  if (!last_raw_) {
    value_ = static_cast<std::int32_t>(raw_counts);
  } else {
    // The modular difference read as signed is the true movement while |movement| < 2^31.
    value_ += static_cast<std::int32_t>(raw_counts - *last_raw_);
  }
  last_raw_ = raw_counts;
  return value_;
}

std::optional<std::int64_t> PositionUnwrapper::value_counts() const {
  if (!last_raw_) return std::nullopt;
  return value_;
}

TimestampUnwrapper::TimestampUnwrapper(double clk_hz) : clk_hz_(clk_hz) {
  if (!(clk_hz > 0.0)) {
    throw std::invalid_argument("TimestampUnwrapper: clk_hz must be positive, got " +
                                std::to_string(clk_hz));
  }
}

std::uint64_t TimestampUnwrapper::update(std::uint32_t raw_cycles) {
  if (!last_raw_) {
    value_ = raw_cycles;
    first_ = raw_cycles;
  } else {
    value_ += static_cast<std::uint32_t>(raw_cycles - *last_raw_);  // time only moves forward
  }
  last_raw_ = raw_cycles;
  return value_;
}

double TimestampUnwrapper::elapsed_ms() const {
  return static_cast<double>(value_ - first_) * 1000.0 / clk_hz_;
}

}  // namespace omniloc::protocol
