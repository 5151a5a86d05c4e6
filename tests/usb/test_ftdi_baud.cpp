// FT2232H H-series baud divisor encoding against the values docs/PROTOCOL.md lists (worked out
// from libftdi1's arithmetic: 12 Mbaud 0x0000, 3 Mbaud 0x0004, 1 Mbaud 0x000C, wIndex 0x0202 for
// channel B) and hand-computed divisors.
#include <gtest/gtest.h>

#include <stdexcept>

#include "omniloc/usb_transport.hpp"

namespace omniloc::ftdi {
namespace {

TEST(FtdiBaud, ChannelBKnownValues) {
  const auto b12 = h_series_baud(12'000'000, kPortB);
  EXPECT_EQ(b12.value, 0x0000);
  EXPECT_EQ(b12.index, 0x0202);
  EXPECT_EQ(b12.actual_baud, 12'000'000u);
  const auto b3 = h_series_baud(3'000'000, kPortB);
  EXPECT_EQ(b3.value, 0x0004);
  EXPECT_EQ(b3.index, 0x0202);
  const auto b1 = h_series_baud(1'000'000, kPortB);
  EXPECT_EQ(b1.value, 0x000C);
  EXPECT_EQ(b1.index, 0x0202);
  EXPECT_EQ(b1.actual_baud, 1'000'000u);
}

TEST(FtdiBaud, SpecialCodesAndFractions) {
  // 8 Mbaud = 12 MHz / 1.5: special code 1; 6 Mbaud = divisor 2: code 2.
  EXPECT_EQ(h_series_baud(8'000'000, kPortB).value, 0x0001);
  EXPECT_EQ(h_series_baud(6'000'000, kPortB).value, 0x0002);
  // 115200: 12e6/115200 = 104.1667 -> 104 1/8 = 833/8: integer 104 (0x68), fraction 1/8 coded 3
  // << 14.
  const auto b = h_series_baud(115'200, kPortB);
  EXPECT_EQ(b.value, 0xC068);
  EXPECT_EQ(b.index, 0x0202);
  EXPECT_EQ(b.actual_baud, 115'246u);  // 12e6 * 8 / 833 = 115246.1
  // Channel A (port index 1) only changes the low byte of wIndex.
  EXPECT_EQ(h_series_baud(1'000'000, 1).index, 0x0201);
}

TEST(FtdiBaud, RejectsRatesItCannotMake) {
  EXPECT_THROW((void)h_series_baud(0, kPortB), std::invalid_argument);
  EXPECT_THROW((void)h_series_baud(13'000'000, kPortB), std::invalid_argument);
  // 10 Mbaud lies between the 12 M and 8 M codes: 20 % off.
  EXPECT_THROW((void)h_series_baud(10'000'000, kPortB), std::invalid_argument);
}

}  // namespace
}  // namespace omniloc::ftdi
