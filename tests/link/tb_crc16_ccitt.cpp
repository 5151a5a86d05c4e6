// crc16_ccitt against a bit-serial reference written from the CRC's definition, and against the
// catalogue check value of CRC-16/CCITT-FALSE ("123456789" -> 0x29B1).
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string_view>

#include "Vcrc16_ccitt.h"
#include "tb_support.hpp"

namespace {

// Bit-serial reference: shift each message bit (MSB first) through the polynomial.
std::uint16_t reference_crc(std::uint16_t crc, std::uint8_t byte) {
  for (int bit = 7; bit >= 0; --bit) {
    const bool in = ((byte >> bit) & 1u) != 0;
    const bool top = (crc & 0x8000u) != 0;
    crc = static_cast<std::uint16_t>(crc << 1);
    if (in != top) crc ^= 0x1021u;
  }
  return crc;
}

std::uint16_t rtl_crc(Vcrc16_ccitt& dut, std::uint16_t crc, std::uint8_t byte) {
  dut.crc_i = crc;
  dut.data_i = byte;
  dut.eval();
  return dut.crc_o;
}

TEST(Crc16Ccitt, CheckValueOf123456789) {
  VerilatedContext ctx;
  Vcrc16_ccitt dut(&ctx);
  std::uint16_t crc = 0xFFFF;
  for (char c : std::string_view("123456789"))
    crc = rtl_crc(dut, crc, static_cast<std::uint8_t>(c));
  EXPECT_EQ(crc, 0x29B1);
}

TEST(Crc16Ccitt, EveryCrcAndByteMatchesBitSerialReference) {
  VerilatedContext ctx;
  Vcrc16_ccitt dut(&ctx);
  std::mt19937_64 rng(omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 1));
  // All 256 bytes against 4096 random CRC states: 10^6 input pairs.
  for (int i = 0; i < 4096; ++i) {
    const auto crc = static_cast<std::uint16_t>(rng());
    for (int b = 0; b < 256; ++b) {
      const auto byte = static_cast<std::uint8_t>(b);
      ASSERT_EQ(rtl_crc(dut, crc, byte), reference_crc(crc, byte))
          << "crc " << crc << " byte " << b;
    }
  }
}

}  // namespace
