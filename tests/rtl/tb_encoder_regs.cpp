// encoder_regs testbench: random bus traffic (known and unknown addresses, accepted and refused
// values, W1C) mixed with random captures, illegal pulses and consume strobes, every cycle
// against a golden model of the register file written from common/regmap.json's semantics.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <Vencoder_regs.h>
#include <omniloc/regmap.hpp>

#include "tb_clocked.hpp"

namespace {

using omniloc::rtl_tb::Clocked;
using omniloc::rtl_tb::TraceRequest;
namespace rm = omniloc::regmap;

constexpr std::uint32_t kDefaultPeriodCycles = 40'000'000 / 100;

struct Inputs {
  std::uint8_t addr = 0;
  bool rd = false;
  bool wr = false;
  std::uint32_t wdata = 0;
  bool capture = false;
  std::uint8_t illegal = 0;
  bool consumed = false;
  std::uint32_t timestamp = 0;
  std::array<std::uint32_t, 4> count{};
  std::array<std::uint32_t, 4> pos{};
  std::uint8_t dir = 0;
  std::array<std::uint32_t, 4> errs{};
  std::uint32_t gyro_sum = 0;  // 24-bit two's complement, as gyro_accum gives it
  std::uint8_t gyro_count = 0;
  std::uint8_t gyro_flags = 0;
};

// Golden register file: state after each clock edge.
struct Model {
  bool enable = false;
  unsigned decode = 0;
  bool stream = false;
  std::uint32_t filter = 0;
  std::uint32_t period = kDefaultPeriodCycles;
  std::uint8_t status = 0;
  bool win_valid = false;
  std::uint32_t seq = 0;
  std::uint32_t snap_seq = 0;
  std::uint32_t win_ts = 0;
  std::uint8_t win_status = 0;
  bool pending = false;
  std::uint32_t snap_ts = 0;
  std::uint8_t snap_status = 0;
  std::uint8_t snap_dir = 0;
  std::array<std::uint32_t, 4> snap_count{};
  std::array<std::uint32_t, 4> snap_pos{};
  std::uint32_t snap_gyro_sum = 0;  // sign-extended to 32 bits
  std::uint8_t snap_gyro_count = 0;
  std::uint8_t snap_gyro_flags = 0;
  std::uint32_t rdata = 0;
  bool ack = false;
  bool err = false;

  void edge(const Inputs& in) {
    Model n = *this;
    const bool rd = in.rd && !in.wr;
    const bool wr = in.wr && !in.rd;
    bool known = true;
    bool writable = false;
    std::uint32_t value = 0;
    switch (in.addr) {
      case rm::kRegId:
        value = rm::kIdValue;
        break;
      case rm::kRegVersion:
        value = rm::kVersionValue;
        break;
      case rm::kRegConfig:
        value = 4;
        break;  // CONFIG.CHANNELS of the default build: four wheels
      case rm::kRegControl:
        value = (enable ? 1u : 0u) | (decode << 1) | (stream ? 8u : 0u);
        writable = true;
        break;
      case rm::kRegFilter:
        value = filter;
        writable = true;
        break;
      case rm::kRegPeriod:
        value = period;
        writable = true;
        break;
      case rm::kRegStatus:
        value = status;
        writable = true;
        break;
      case rm::kRegTimestamp:
        value = in.timestamp;
        break;
      case rm::kRegSnapSeq:
        value = seq;
        break;
      case rm::kRegSnapTimestamp:
        value = snap_ts;
        break;
      case rm::kRegSnapDir:
        value = snap_dir;
        break;
      case rm::kRegSnapStatus:
        value = snap_status;
        break;
      case rm::kRegSnapGyroSum:
        value = snap_gyro_sum;
        break;
      case rm::kRegSnapGyro:
        value = snap_gyro_count | static_cast<std::uint32_t>(snap_gyro_flags) << 8;
        break;
      default:
        if (in.addr >= rm::kRegSnapCount0 && in.addr <= rm::kRegSnapCount3) {
          value = snap_count[in.addr - rm::kRegSnapCount0];
        } else if (in.addr >= rm::kRegSnapPosition0 && in.addr <= rm::kRegSnapPosition3) {
          value = snap_pos[in.addr - rm::kRegSnapPosition0];
        } else if (in.addr >= rm::kRegErrorCount0 && in.addr <= rm::kRegErrorCount3) {
          value = in.errs[in.addr - rm::kRegErrorCount0];
        } else {
          known = false;
        }
    }
    bool refused = false;
    if (wr && in.addr == rm::kRegControl) {
      if ((in.wdata >> 4) != 0 || ((in.wdata >> 1) & 3) == 3) {
        refused = true;
      } else {
        n.enable = in.wdata & 1;
        n.decode = (in.wdata >> 1) & 3;
        n.stream = (in.wdata >> 3) & 1;
      }
    }
    if (wr && in.addr == rm::kRegFilter) {
      if (in.wdata > 255)
        refused = true;
      else
        n.filter = in.wdata;
    }
    if (wr && in.addr == rm::kRegPeriod) {
      if (in.wdata < rm::kPeriodMinCycles)
        refused = true;
      else
        n.period = in.wdata;
    }
    const bool latch = rd && in.addr == rm::kRegSnapSeq;
    const bool consumed = latch || in.consumed;
    const bool overrun = in.capture && pending && !consumed;
    std::uint8_t next_status = status;
    if (wr && in.addr == rm::kRegStatus) next_status &= static_cast<std::uint8_t>(~in.wdata & 0x7F);
    // GYRO_FAULT: in the cycle after a capture the gyro inputs hold that window's flags.
    const bool gyro_fault = win_valid && in.gyro_flags != 0;
    next_status |= static_cast<std::uint8_t>((in.illegal & 0xF) | (overrun ? 0x10 : 0) |
                                             (refused ? 0x20 : 0) | (gyro_fault ? 0x40 : 0));
    n.status = next_status;
    n.win_valid = in.capture;
    if (in.capture) {
      n.seq = seq + 1;
      n.win_ts = in.timestamp;
      n.win_status = next_status;
      n.pending = true;
    } else if (consumed) {
      n.pending = false;
    }
    if (consumed) {  // SNAP_SEQ read or win_consumed_i: the frozen bank takes the window
      n.snap_seq = seq;
      n.snap_ts = win_ts;
      n.snap_status = win_status;
      n.snap_dir = in.dir;
      n.snap_count = in.count;
      n.snap_pos = in.pos;
      n.snap_gyro_sum = (in.gyro_sum & 0x800000u) ? (in.gyro_sum | 0xFF000000u) : in.gyro_sum;
      n.snap_gyro_count = in.gyro_count;
      n.snap_gyro_flags = in.gyro_flags;
    }
    n.ack = in.rd || in.wr;
    n.err = (in.rd && in.wr) || (rd && !known) || (wr && (!known || !writable)) || refused;
    n.rdata = rd ? value : 0;
    *this = n;
  }
};

// The frozen bank as a WINDOW body (seq, timestamp, counts, dir, status, gyro sum, count, flags),
// as the link sends it.
std::vector<std::uint8_t> bank_body(const Model& m) {
  std::vector<std::uint8_t> b;
  auto put = [&](std::uint32_t v) {
    for (int k = 0; k < 4; ++k) b.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
  };
  put(m.snap_seq);
  put(m.snap_ts);
  for (auto c : m.snap_count) put(c);
  b.push_back(m.snap_dir);
  b.push_back(m.snap_status);
  put(m.snap_gyro_sum);
  b.push_back(m.snap_gyro_count);
  b.push_back(m.snap_gyro_flags);
  return b;
}

// idx: the bank byte to check this cycle (kFrameTelemetryBodyBytes = past the body, reads 0).
std::string compare(Vencoder_regs& d, const Model& m, unsigned idx = 0) {
  auto field = [](const char* name, std::uint64_t got, std::uint64_t want) {
    return got == want ? std::string()
                       : std::string(name) + " " + std::to_string(got) + " != golden " +
                             std::to_string(want);
  };
  const auto body = bank_body(m);
  d.bank_idx_i = static_cast<std::uint8_t>(idx);
  d.eval();
  if (auto s = field("bank_byte_o", d.bank_byte_o, idx < body.size() ? body[idx] : 0); !s.empty())
    return s + " (bank byte " + std::to_string(idx) + ")";
  for (const auto& s :
       {field("reg_ack_o", d.reg_ack_o, m.ack), field("reg_err_o", d.reg_err_o, m.err),
        field("reg_rdata_o", d.reg_rdata_o, m.rdata), field("enable_o", d.enable_o, m.enable),
        field("decode_o", d.decode_o, m.decode), field("stream_o", d.stream_o, m.stream),
        field("filter_len_o", d.filter_len_o, m.filter), field("period_o", d.period_o, m.period),
        field("status_o", d.status_o, m.status), field("win_valid_o", d.win_valid_o, m.win_valid),
        field("win_seq_o", d.win_seq_o, m.seq),
        field("win_timestamp_o", d.win_timestamp_o, m.win_ts),
        field("win_status_o", d.win_status_o, m.win_status)}) {
    if (!s.empty()) return s;
  }
  return {};
}

struct Result {
  std::string failure;
  std::uint64_t fail_cycle = 0;
  std::uint64_t refused = 0;
  std::uint64_t errors = 0;
  std::uint64_t overruns = 0;
};

Result run(std::uint64_t seed, std::uint64_t cycles, const TraceRequest* trace) {
  std::mt19937_64 rng(seed);
  Result res;
  Clocked<Vencoder_regs> dut(trace);
  Model model;
  dut.reset(2);
  if (auto s = compare(dut.io(), model); !s.empty()) return res.failure = "after reset: " + s, res;
  Inputs in;
  // The bus is pipelined (docs/RTL.md): a request presented before edge e takes effect at edge e+1
  // exactly as the golden register file takes it, and its answer is visible after edge e+2. So the
  // golden model gets the request one edge late and its answer is shown one edge later again.
  Inputs prev_req;
  struct Answer {
    bool ack = false;
    bool err = false;
    std::uint32_t rdata = 0;
  } answer;
  const std::array<std::uint8_t, 10> hot = {
      rm::kRegControl,     rm::kRegFilter,     rm::kRegPeriod,     rm::kRegStatus,
      rm::kRegSnapSeq,     rm::kRegSnapCount2, rm::kRegSnapStatus, rm::kRegId,
      rm::kRegSnapGyroSum, rm::kRegSnapGyro};
  for (std::uint64_t i = 0; i < cycles; ++i) {
    const unsigned r = static_cast<unsigned>(rng() % 100);
    in.rd = r < 35 || r >= 98;
    in.wr = (r >= 35 && r < 60) || r >= 98;
    in.addr = (rng() % 4 == 0) ? static_cast<std::uint8_t>(rng() % 256) : hot[rng() % hot.size()];
    switch (rng() % 6) {
      case 0:
        in.wdata = static_cast<std::uint32_t>(rng());
        break;
      case 1:
        in.wdata = static_cast<std::uint32_t>(rng() % 16);
        break;  // CONTROL-like
      case 2:
        in.wdata = static_cast<std::uint32_t>(rng() % 300);
        break;  // FILTER-like
      case 3:
        in.wdata = static_cast<std::uint32_t>(60 + rng() % 8);
        break;  // around PERIOD_MIN
      case 4:
        in.wdata = 0x7F;
        break;  // clear all flags
      default:
        in.wdata = static_cast<std::uint32_t>(1u << (rng() % 7));
        break;
    }
    in.capture = rng() % 23 == 0;
    in.illegal = (rng() % 40 == 0) ? static_cast<std::uint8_t>(rng() % 16) : 0;
    in.consumed = rng() % 30 == 0;
    in.timestamp = static_cast<std::uint32_t>(dut.cycle());
    if (in.capture || i == 0) {
      for (int ch = 0; ch < 4; ++ch) {
        in.count[ch] = static_cast<std::uint32_t>(rng());
        in.pos[ch] = static_cast<std::uint32_t>(rng());
        in.errs[ch] = static_cast<std::uint32_t>(rng()) & 0xFFu;  // ERROR_COUNT_BITS = 8
      }
      in.dir = static_cast<std::uint8_t>(rng() % 16);
      in.gyro_sum = static_cast<std::uint32_t>(rng()) & 0xFFFFFFu;
      in.gyro_count = static_cast<std::uint8_t>(rng());
      in.gyro_flags = rng() % 2 == 0 ? 0 : static_cast<std::uint8_t>(rng() % 128);
    }
    dut->reg_addr_i = in.addr;
    dut->reg_rd_i = in.rd;
    dut->reg_wr_i = in.wr;
    dut->reg_wdata_i = in.wdata;
    dut->capture_i = in.capture;
    dut->illegal_i = in.illegal;
    dut->win_consumed_i = in.consumed;
    dut->timestamp_i = in.timestamp;
    dut->err_count_i = 0;
    for (int ch = 0; ch < 4; ++ch) {
      dut->win_count_i[ch] = in.count[ch];
      dut->win_position_i[ch] = in.pos[ch];
      dut->err_count_i |= in.errs[ch] << (8 * ch);  // four 8-bit saturating counters, channel 0 low
    }
    dut->win_dir_i = in.dir;
    dut->gyro_sum_i = in.gyro_sum;
    dut->gyro_count_i = in.gyro_count;
    dut->gyro_flags_i = in.gyro_flags;
    const std::uint64_t e = dut.cycle();
    const bool had_overrun = (model.status & 0x10) != 0;
    dut.step();
    Inputs delayed = in;
    delayed.addr = prev_req.addr;
    delayed.rd = prev_req.rd;
    delayed.wr = prev_req.wr;
    delayed.wdata = prev_req.wdata;
    prev_req = in;
    model.edge(delayed);
    Model shown = model;
    shown.ack = answer.ack;
    shown.err = answer.err;
    shown.rdata = answer.rdata;
    answer = {model.ack, model.err, model.rdata};
    if (auto s =
            compare(dut.io(), shown, static_cast<unsigned>(e % (rm::kFrameTelemetryBodyBytes + 1)));
        !s.empty()) {
      res.failure = "edge " + std::to_string(e) + ": " + s;
      res.fail_cycle = e;
      return res;
    }
    res.errors += model.err;
    res.refused += model.err && delayed.wr && !delayed.rd;
    res.overruns += !had_overrun && (model.status & 0x10);
  }
  return res;
}

TEST(EncoderRegs, MatchesGoldenRegisterFile) {
  const std::uint64_t seed = omniloc::rtl_tb::test_seed("encoder_regs", 2718);
  const auto res = run(seed, 1'000'000, nullptr);
  std::cout << "[encoder_regs] bus errors=" << res.errors
            << " refused or read-only writes=" << res.refused << " overrun events=" << res.overruns
            << "\n";
  if (!res.failure.empty()) {
    const TraceRequest tr{omniloc::rtl_tb::trace_path("encoder_regs", seed),
                          res.fail_cycle > 2000 ? res.fail_cycle - 2000 : 0};
    run(seed, res.fail_cycle + 1, &tr);
    FAIL() << res.failure << " seed " << seed << "; trace: " << tr.path;
  }
  EXPECT_GT(res.refused, 1000u);
  EXPECT_GT(res.overruns, 100u);
}

}  // namespace
