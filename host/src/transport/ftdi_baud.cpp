// FTDI H-series baud-rate divisor encoding (the same arithmetic as libftdi1's ftdi_to_clkbits,
// written from the chip's documented divisor format).
#include <cmath>
#include <stdexcept>
#include <string>

#include "omniloc/usb_transport.hpp"

namespace omniloc::ftdi {

namespace {

struct Encoded {
  std::uint32_t divisor;  ///< the 17-bit encoded divisor (before the H-clock flag)
  std::uint32_t baud;
};

Encoded to_clkbits(std::uint32_t baud, std::uint32_t clk_hz, std::uint32_t clk_div) {
  static constexpr std::uint32_t kFracCode[8] = {0, 3, 2, 4, 1, 5, 6, 7};
  // Three special codes for the fastest rates: divisor 1, 1.5 and 2.
  if (baud >= clk_hz / clk_div) return {0, clk_hz / clk_div};
  if (baud >= clk_hz / (clk_div + clk_div / 2)) return {1, clk_hz / (clk_div + clk_div / 2)};
  if (baud >= clk_hz / (2 * clk_div)) return {2, clk_hz / (2 * clk_div)};
  // Divisor in 1/8 steps, rounded to nearest: compute in 1/16 and round the last bit.
  const std::uint64_t div16 = static_cast<std::uint64_t>(clk_hz) * 16 / clk_div / baud;
  std::uint64_t div8 = (div16 & 1) ? div16 / 2 + 1 : div16 / 2;
  if (div8 > 0x20000) div8 = 0x1FFFF;
  std::uint64_t best2 = static_cast<std::uint64_t>(clk_hz) * 16 / clk_div / div8;
  const std::uint64_t best = (best2 & 1) ? best2 / 2 + 1 : best2 / 2;
  const auto enc = static_cast<std::uint32_t>((div8 >> 3) | (kFracCode[div8 & 7] << 14));
  return {enc, static_cast<std::uint32_t>(best)};
}

}  // namespace

BaudSetting h_series_baud(std::uint32_t baud, std::uint16_t port_index) {
  constexpr std::uint32_t kHClk = 120'000'000;
  constexpr std::uint32_t kCClk = 48'000'000;
  if (baud < 183 || baud > 12'000'000) {
    throw std::invalid_argument("FT2232H baud rate " + std::to_string(baud) +
                                " out of range 183..12000000");
  }
  Encoded e{};
  if (static_cast<std::uint64_t>(baud) * 10 > kHClk / 0x3FFF) {
    e = to_clkbits(baud, kHClk, 10);
    e.divisor |= 0x20000;  // select the 120 MHz clock
  } else {
    e = to_clkbits(baud, kCClk, 16);
  }
  const double err = std::abs(static_cast<double>(e.baud) - baud) / baud;
  if (err > 0.03) {
    throw std::invalid_argument("FT2232H cannot make " + std::to_string(baud) +
                                " baud: nearest is " + std::to_string(e.baud) + " baud");
  }
  BaudSetting s;
  s.value = static_cast<std::uint16_t>(e.divisor & 0xFFFF);
  s.index = static_cast<std::uint16_t>(((e.divisor >> 8) & 0xFF00) | port_index);
  s.actual_baud = e.baud;
  return s;
}

}  // namespace omniloc::ftdi
