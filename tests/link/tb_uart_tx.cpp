// uart_tx against a golden 8N1 line decoder: every byte, in order, with every bit exactly
// CLKS_PER_BIT cycles long (12 at the default 12 MHz / 1 Mbaud), the line high when idle.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "Vuart_tx.h"
#include "omniloc/regmap.hpp"
#include "tb_clocked.hpp"

namespace {

// The module's defaults are the board's clock and baud (common/regmap.json "link"): 12 cycles a
// bit.
constexpr int kClksPerBit =
    static_cast<int>(omniloc::regmap::kBoardClockHz / omniloc::regmap::kUartBaud);

struct Decoded {
  std::vector<std::uint8_t> bytes;
  std::vector<std::string> errors;
};

// Golden decoder of a recorded line: a frame starts at a high-to-low edge; each bit must hold for
// exactly kClksPerBit cycles; the stop bit must stay high for at least kClksPerBit cycles.
Decoded decode_line(const std::vector<std::uint8_t>& line) {
  Decoded out;
  std::size_t t = 1;
  while (t < line.size()) {
    if (!(line[t - 1] == 1 && line[t] == 0)) {
      ++t;
      continue;
    }
    if (t + 10 * kClksPerBit > line.size()) {
      out.errors.push_back("frame cut off by the end of the run at cycle " + std::to_string(t));
      break;
    }
    std::uint8_t byte = 0;
    for (int bit = 0; bit < 10; ++bit) {
      const std::uint8_t level = line[t + bit * kClksPerBit];
      for (int c = 0; c < kClksPerBit; ++c) {
        if (line[t + bit * kClksPerBit + c] != level) {
          out.errors.push_back("bit " + std::to_string(bit) + " of the frame at cycle " +
                               std::to_string(t) + " changes inside its bit time");
        }
      }
      if (bit == 0 && level != 0) out.errors.push_back("start bit high at " + std::to_string(t));
      if (bit >= 1 && bit <= 8) byte |= static_cast<std::uint8_t>(level << (bit - 1));
      if (bit == 9 && level != 1) out.errors.push_back("stop bit low at " + std::to_string(t));
    }
    out.bytes.push_back(byte);
    t += 10 * kClksPerBit;
  }
  return out;
}

// Sends `bytes` with random idle gaps; returns the recorded line.
std::vector<std::uint8_t> run(const std::vector<std::uint8_t>& bytes, std::uint64_t seed,
                              bool back_to_back, const std::string& vcd = {}) {
  const omniloc::rtl_tb::TraceRequest trace{vcd, 0};
  omniloc::rtl_tb::Clocked<Vuart_tx> bench(vcd.empty() ? nullptr : &trace);
  auto& dut = bench.io();
  std::mt19937_64 rng(seed);
  bench.reset();
  std::vector<std::uint8_t> line{dut.tx_o};  // the idle level before the first start bit
  std::size_t next = 0;
  int gap = 0;
  while (next < bytes.size() || !dut.ready_o) {
    dut.valid_i = 0;
    if (next < bytes.size() && gap == 0) {
      dut.valid_i = 1;
      dut.data_i = bytes[next];
    }
    const bool accepted = dut.valid_i && dut.ready_o;
    bench.step();
    line.push_back(dut.tx_o);
    if (accepted) {
      ++next;
      gap = back_to_back ? 0 : static_cast<int>(rng() % 40);
    } else if (gap > 0) {
      --gap;
    }
  }
  for (int i = 0; i < 2 * kClksPerBit; ++i) {
    bench.step();
    line.push_back(dut.tx_o);
  }
  return line;
}

void check(std::uint64_t seed, bool back_to_back) {
  std::mt19937_64 rng(seed);
  std::vector<std::uint8_t> bytes(3000);
  for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
  const auto decoded = decode_line(run(bytes, seed, back_to_back));
  const bool ok = decoded.errors.empty() && decoded.bytes == bytes;
  if (!ok) {
    const auto vcd = omniloc::rtl_tb::trace_path(back_to_back ? "uart_tx_b2b" : "uart_tx", seed);
    run(bytes, seed, back_to_back, vcd);
    ADD_FAILURE() << "trace: " << vcd;
  }
  ASSERT_TRUE(decoded.errors.empty())
      << decoded.errors.size() << " line errors, the first: " << decoded.errors.front();
  ASSERT_EQ(decoded.bytes.size(), bytes.size());
  EXPECT_EQ(decoded.bytes, bytes);
}

TEST(UartTx, RandomBytesWithGapsDecodeExactly) {
  check(omniloc::rtl_tb::test_seed(::testing::UnitTest::GetInstance()->current_test_info()->name(),
                                   11),
        false);
}

TEST(UartTx, BackToBackBytesDecodeExactly) {
  check(omniloc::rtl_tb::test_seed(::testing::UnitTest::GetInstance()->current_test_info()->name(),
                                   12),
        true);
}

}  // namespace
