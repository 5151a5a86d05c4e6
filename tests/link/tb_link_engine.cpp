// link_engine against a golden register-file model and a golden response rule: random reads and
// writes (known, unknown and read-only addresses, refused values), snapshot requests, parser
// errors, and telemetry streaming of windows, with a transmitter that is busy for random times.
#include <gtest/gtest.h>

#include <cstdint>
#include <deque>
#include <map>
#include <random>
#include <vector>

#include "Vlink_engine.h"
#include "golden_frames.hpp"
#include "tb_clocked.hpp"

namespace {

namespace rm = omniloc::regmap;

struct Frame {
  std::uint8_t type;
  std::vector<std::uint8_t> body;
  bool operator==(const Frame&) const = default;
};

std::ostream& operator<<(std::ostream& os, const Frame& f) {
  os << "type " << int(f.type) << " body";
  for (auto b : f.body) os << ' ' << int(b);
  return os;
}

// Golden register file: the regmap's addresses, with RW/W1C writable and PERIOD refusing values
// below the minimum (the "refused value" case).
struct RegisterModel {
  std::map<std::uint8_t, std::uint32_t> values;
  std::vector<std::uint8_t> reads;  // addresses read, in order
  explicit RegisterModel(std::mt19937_64& rng) {
    for (const auto& r : rm::kRegisters) values[r.address] = static_cast<std::uint32_t>(rng());
  }
  static const rm::Register* find(std::uint8_t a) {
    for (const auto& r : rm::kRegisters)
      if (r.address == a) return &r;
    return nullptr;
  }
  // Returns {error, data}.
  std::pair<bool, std::uint32_t> read(std::uint8_t a) {
    reads.push_back(a);
    if (!find(a)) return {true, 0};
    return {false, values[a]};
  }
  bool write(std::uint8_t a, std::uint32_t v) {
    const auto* r = find(a);
    if (!r || (r->access != rm::Access::kReadWrite && r->access != rm::Access::kWriteOneToClear))
      return true;
    if (a == rm::kRegPeriod && v < rm::kPeriodMinCycles) return true;
    values[a] = v;
    return false;
  }
};

// The frozen window bank of encoder_regs as the link reads it: byte k at bank_byte_i when tx_idx_i
// = k.
void drive_bank(Vlink_engine& dut, const std::vector<std::uint8_t>& bank) {
  dut.bank_byte_i = dut.tx_idx_i < bank.size() ? bank[dut.tx_idx_i] : 0;
}

// The body as frame_tx reads it: byte k through tx_idx_i / tx_byte_o (combinational).
std::vector<std::uint8_t> body_bytes(Vlink_engine& dut, const std::vector<std::uint8_t>& bank,
                                     int n) {
  std::vector<std::uint8_t> b;
  const auto idx = dut.tx_idx_i;
  for (int k = 0; k < n; ++k) {
    dut.tx_idx_i = static_cast<std::uint8_t>(k);
    drive_bank(dut, bank);
    dut.eval();
    b.push_back(dut.tx_byte_o);
  }
  dut.tx_idx_i = idx;
  drive_bank(dut, bank);
  dut.eval();
  return b;
}

struct Window {
  std::uint32_t seq, ts;
  std::uint32_t count[4];
  std::uint8_t dir, status;
  std::uint32_t gyro_sum;
  std::uint8_t gyro_count, gyro_flags;
  [[nodiscard]] std::vector<std::uint8_t> body() const {
    std::vector<std::uint8_t> b;
    omniloc::tb::put_u32(b, seq);
    omniloc::tb::put_u32(b, ts);
    for (auto c : count) omniloc::tb::put_u32(b, c);
    b.push_back(dir);
    b.push_back(status);
    omniloc::tb::put_u32(b, gyro_sum);
    b.push_back(gyro_count);
    b.push_back(gyro_flags);
    return b;
  }
};

TEST(LinkEngine, RequestsSnapshotsAndStreamingMatchGoldenModel) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 51);
  std::mt19937_64 rng(seed);
  omniloc::rtl_tb::Clocked<Vlink_engine> bench;
  auto& dut = bench.io();
  bench.reset();
  RegisterModel regs(rng);

  std::vector<Frame> expected_responses, responses, telemetry, expected_telemetry;
  int pending_bus = -1;  // cycles until the model acks; -1 none
  bool bus_err = false;
  std::uint32_t bus_data = 0;
  int tx_busy = 0;
  Frame sending{};
  int sending_len = -1;
  std::vector<std::uint8_t> bank(
      rm::kFrameTelemetryBodyBytes,
      0);  // the frozen bank (latched by SNAP_SEQ reads and win_consumed_o)
  std::vector<std::size_t>
      snapshot_answers;  // expected_responses slots waiting for their SNAP_SEQ read
  int requests_left = 3000;
  bool event_up = false;
  int next_window_in = 700;
  Window win{};
  std::uint32_t seq = 0;
  int consumed = 0;
  bool stream = false;

  int drain = 2000;  // cycles to run on after the last request, for its answer to leave
  for (std::uint64_t cycle = 0; cycle < 4'000'000 && drain > 0; ++cycle) {
    if (requests_left == 0 && !event_up) --drain;
    // Offer a new event when the previous one was taken.
    if (!event_up && requests_left > 0 && rng() % 4 == 0) {
      event_up = true;
      --requests_left;
      const int kind = static_cast<int>(rng() % 10);
      dut.ev_error_i = 0;
      dut.ev_read_i = 0;
      dut.ev_write_i = 0;
      dut.ev_data_i = static_cast<std::uint32_t>(rng());
      // Mostly known addresses, sometimes any byte.
      dut.ev_addr_i = rng() % 4 ? rm::kRegisters[rng() % rm::kRegisters.size()].address
                                : static_cast<std::uint8_t>(rng());
      if (kind < 4) {
        dut.ev_code_i = rm::kFrameReadReq;
        dut.ev_read_i = 1;  // frame_rx's decoded kind, as its proof states it
      } else if (kind < 7) {
        dut.ev_code_i = rm::kFrameWriteReq;
        dut.ev_write_i = 1;
        if (rng() % 3 == 0)
          dut.ev_addr_i = rm::kRegPeriod, dut.ev_data_i = static_cast<std::uint32_t>(rng() % 128);
      } else if (kind < 9) {
        dut.ev_code_i = rm::kFrameSnapshotReq;
      } else {
        dut.ev_error_i = 1;
        dut.ev_code_i = rng() % 2 ? rm::kErrBadCrc : rm::kErrMalformed;
      }
    }
    dut.ev_valid_i = event_up;

    // Windows from the core; streaming toggles now and then.
    dut.win_valid_i = 0;
    if (--next_window_in == 0) {
      next_window_in = 700 + static_cast<int>(rng() % 800);
      win = {++seq,
             static_cast<std::uint32_t>(rng()),
             {},
             static_cast<std::uint8_t>(rng() % 16),
             static_cast<std::uint8_t>(rng()),
             static_cast<std::uint32_t>(rng()),
             static_cast<std::uint8_t>(rng()),
             static_cast<std::uint8_t>(rng())};
      for (auto& c : win.count) c = static_cast<std::uint32_t>(rng());
      if (rng() % 10 == 0) stream = !stream;
      dut.win_valid_i = 1;
      if (stream) expected_telemetry.push_back({rm::kFrameTelemetry, win.body()});
    }
    dut.stream_en_i = stream;

    // Register bus: ack one cycle after the strobe, like encoder_regs.
    dut.reg_ack_i = 0;
    if (pending_bus == 0) {
      dut.reg_ack_i = 1;
      dut.reg_err_i = bus_err;
      dut.reg_rdata_i = bus_data;
      pending_bus = -1;
    }

    // Transmitter: busy for a while after each frame.
    dut.tx_ready_i = tx_busy == 0;

    // Sample handshakes that happen at this edge.
    const bool ev_taken = dut.ev_valid_i && dut.ev_ready_o;
    if (ev_taken) {
      const std::uint8_t a = dut.ev_addr_i;
      if (dut.ev_error_i) {
        expected_responses.push_back({rm::kFrameError, {dut.ev_code_i, a}});
      } else if (dut.ev_code_i == rm::kFrameReadReq) {
        const auto* r = RegisterModel::find(a);
        if (!r) {
          expected_responses.push_back({rm::kFrameError, {rm::kErrBadAddress, a}});
        } else {
          std::vector<std::uint8_t> b{a};
          omniloc::tb::put_u32(b, regs.values[a]);
          expected_responses.push_back({rm::kFrameReadResp, b});
        }
      } else if (dut.ev_code_i == rm::kFrameWriteReq) {
        const auto* r = RegisterModel::find(a);
        const bool writable =
            r && (r->access == rm::Access::kReadWrite || r->access == rm::Access::kWriteOneToClear);
        if (!r)
          expected_responses.push_back({rm::kFrameError, {rm::kErrBadAddress, a}});
        else if (!writable)
          expected_responses.push_back({rm::kFrameError, {rm::kErrReadOnly, a}});
        else if (a == rm::kRegPeriod && dut.ev_data_i < rm::kPeriodMinCycles)
          expected_responses.push_back({rm::kFrameError, {rm::kErrBadValue, a}});
        else
          expected_responses.push_back({rm::kFrameWriteAck, {a}});
      } else {
        // The answer is the window latched by the SNAP_SEQ read that follows.
        snapshot_answers.push_back(expected_responses.size());
        expected_responses.push_back({rm::kFrameSnapshotResp, {}});
      }
      event_up = false;
    }
    bool latch = dut.win_consumed_o;  // the bank takes the live window at this edge
    if (dut.reg_rd_o || dut.reg_wr_o) {
      ASSERT_FALSE(dut.reg_rd_o && dut.reg_wr_o);
      if (dut.reg_rd_o && dut.reg_addr_o == rm::kRegSnapSeq) {
        latch = true;
        if (!snapshot_answers.empty()) {
          expected_responses[snapshot_answers.front()].body = win.body();
          snapshot_answers.erase(snapshot_answers.begin());
        }
      }
      ASSERT_EQ(pending_bus, -1) << "a second bus access before the ack";
      if (dut.reg_rd_o) {
        std::tie(bus_err, bus_data) = regs.read(dut.reg_addr_o);
      } else {
        bus_err = regs.write(dut.reg_addr_o, dut.reg_wdata_o);
        bus_data = 0;
      }
      pending_bus = 0;
    }
    if (dut.tx_start_o && dut.tx_ready_i) {
      // frame_tx reads the body from its fourth byte on (after SYNC, LEN, TYPE): read it then.
      sending = {dut.tx_type_o, {}};
      sending_len = dut.tx_body_len_o;
      tx_busy = 3 + static_cast<int>(rng() % 200);
    } else if (tx_busy > 0) {
      if (sending_len >= 0) {
        sending.body = body_bytes(dut, bank, sending_len);
        (sending.type == rm::kFrameTelemetry ? telemetry : responses).push_back(sending);
        sending_len = -1;
      } else if (rng() % 8 == 0 || tx_busy == 1) {
        // The body must stay as it was while the frame is on the line.
        ASSERT_EQ(body_bytes(dut, bank, static_cast<int>(sending.body.size())), sending.body)
            << "body changed mid-frame";
      }
      --tx_busy;
    }
    if (dut.win_consumed_o) ++consumed;
    const auto live = win.body();
    drive_bank(dut, bank);
    bench.step();
    if (latch) bank = live;
  }
  ASSERT_EQ(responses.size(), expected_responses.size());
  for (std::size_t i = 0; i < responses.size(); ++i)
    ASSERT_EQ(responses[i], expected_responses[i]) << "response " << i;
  ASSERT_EQ(telemetry.size(), expected_telemetry.size());
  for (std::size_t i = 0; i < telemetry.size(); ++i)
    ASSERT_EQ(telemetry[i], expected_telemetry[i]) << "telemetry " << i;
  EXPECT_EQ(consumed, static_cast<int>(telemetry.size()));
  std::printf("%zu responses and %zu telemetry frames checked\n", responses.size(),
              telemetry.size());
  EXPECT_GT(telemetry.size(), 100u);
}

}  // namespace
