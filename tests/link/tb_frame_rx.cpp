// frame_rx against a golden parser of the frame rules (rtl/frame_rx.v header): a stream of valid
// requests mixed with bad CRCs, unknown types, wrong and oversized lengths, truncated frames
// (long gaps) and garbage, fed with random gaps, and an event consumer that stalls.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "Vframe_rx.h"
#include "golden_frames.hpp"
#include "tb_clocked.hpp"

namespace {

namespace rm = omniloc::regmap;
constexpr int kTimeoutCycles = 200;  // matches -GTIMEOUT_CYCLES in CMakeLists.txt
constexpr int kMaxLen = 6;

struct Byte {
  std::uint8_t value;
  int gap_before;  // idle cycles before the byte is offered
};

struct Event {
  bool error;
  std::uint8_t code;
  std::uint8_t addr;
  std::uint32_t data;
  bool operator==(const Event&) const = default;
};

std::ostream& operator<<(std::ostream& os, const Event& e) {
  return os << (e.error ? "error " : "request ") << int(e.code) << " addr/detail " << int(e.addr)
            << " data " << e.data;
}

// The golden parser: same rules as the RTL, written from its specification.
std::vector<Event> golden_parse(const std::vector<Byte>& stream) {
  std::vector<Event> events;
  std::vector<std::uint8_t> frame;  // LEN, TYPE, body, CRC
  bool in_frame = false;
  for (const auto& b : stream) {
    if (in_frame && b.gap_before > kTimeoutCycles) {
      events.push_back({true, rm::kErrMalformed, 0xFF, 0});
      in_frame = false;
    }
    if (!in_frame) {
      if (b.value == rm::kFrameSync) {
        in_frame = true;
        frame.clear();
      }
      continue;
    }
    frame.push_back(b.value);
    const std::uint8_t len = frame[0];
    if (frame.size() == 1 && (len == 0 || len > kMaxLen)) {
      events.push_back({true, rm::kErrMalformed, len, 0});
      in_frame = false;
      continue;
    }
    if (frame.size() < static_cast<std::size_t>(len) + 3) continue;
    in_frame = false;
    const std::uint8_t type = frame[1];
    const std::uint16_t crc = omniloc::tb::golden_crc(frame.data(), len + 1);
    const std::uint16_t got = static_cast<std::uint16_t>(frame[len + 1] << 8 | frame[len + 2]);
    if (crc != got) {
      events.push_back({true, rm::kErrBadCrc, type, 0});
      continue;
    }
    const std::size_t body = len - 1u;
    if (type == rm::kFrameReadReq && body == rm::kFrameReadReqBodyBytes) {
      events.push_back({false, type, frame[2], 0});
    } else if (type == rm::kFrameWriteReq && body == rm::kFrameWriteReqBodyBytes) {
      const std::uint32_t data =
          frame[3] | frame[4] << 8 | frame[5] << 16 | static_cast<std::uint32_t>(frame[6]) << 24;
      events.push_back({false, type, frame[2], data});
    } else if (type == rm::kFrameSnapshotReq && body == rm::kFrameSnapshotReqBodyBytes) {
      events.push_back({false, type, 0, 0});
    } else {
      events.push_back({true, rm::kErrMalformed, type, 0});
    }
  }
  return events;
}

std::vector<Byte> make_stream(std::uint64_t seed, int items) {
  std::mt19937_64 rng(seed);
  std::vector<Byte> s;
  auto append = [&](const std::vector<std::uint8_t>& bytes) {
    for (auto v : bytes) s.push_back({v, static_cast<int>(rng() % 8 == 0 ? rng() % 40 : 0)});
  };
  for (int i = 0; i < items; ++i) {
    const auto addr = static_cast<std::uint8_t>(rng());
    const auto data = static_cast<std::uint32_t>(rng());
    std::vector<std::uint8_t> body;
    std::uint8_t type = rm::kFrameReadReq;
    switch (rng() % 10) {
      case 0:
        type = rm::kFrameReadReq;
        body = {addr};
        break;
      case 1:
        type = rm::kFrameWriteReq;
        body = {addr};
        omniloc::tb::put_u32(body, data);
        break;
      case 2:
        type = rm::kFrameSnapshotReq;
        break;
      case 3:
        type = static_cast<std::uint8_t>(rng());
        body.resize(rng() % 6);
        break;  // unknown type, valid CRC
      case 4:
        type = rm::kFrameWriteReq;
        body = {addr, 1, 2};
        break;  // wrong length
      default:
        break;
    }
    auto frame = omniloc::tb::golden_frame(type, body);
    switch (rng() % 10) {
      case 0:
        frame[2 + rng() % (frame.size() - 2)] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
        break;
      case 1:
        frame[1] = static_cast<std::uint8_t>(7 + rng() % 200);
        break;  // oversized LEN
      case 2:
        frame.resize(2 + rng() % (frame.size() - 2));
        break;  // truncated
      default:
        break;
    }
    append(frame);
    if (rng() % 5 == 0) {  // garbage, which may contain SYNC bytes
      std::vector<std::uint8_t> junk(rng() % 12);
      for (auto& j : junk) j = static_cast<std::uint8_t>(rng() % 3 == 0 ? rm::kFrameSync : rng());
      append(junk);
    }
    // A gap long enough to end any truncated frame before the next item.
    s.push_back({static_cast<std::uint8_t>(rng() % 2 ? 0x00 : 0x11), kTimeoutCycles * 2});
  }
  return s;
}

std::vector<Event> run(const std::vector<Byte>& stream, std::uint64_t seed,
                       const std::string& vcd = {}) {
  const omniloc::rtl_tb::TraceRequest trace{vcd, 0};
  omniloc::rtl_tb::Clocked<Vframe_rx> bench(vcd.empty() ? nullptr : &trace);
  auto& dut = bench.io();
  std::mt19937_64 rng(seed ^ 0x5A5A);
  bench.reset();
  std::vector<Event> events;
  std::size_t next = 0;
  int wait = stream.empty() ? 0 : stream[0].gap_before;
  for (int tail = 0; tail < 3 * kTimeoutCycles;) {
    dut.byte_valid_i = 0;
    if (next < stream.size() && wait == 0) {
      dut.byte_valid_i = 1;
      dut.byte_i = stream[next].value;
    }
    dut.ev_ready_i = (rng() % 3) != 0;
    const bool took = dut.byte_valid_i && dut.byte_ready_o;
    if (dut.ev_valid_o && dut.ev_ready_i) {
      events.push_back({dut.ev_error_o != 0, dut.ev_code_o, dut.ev_addr_o, dut.ev_data_o});
      // The decoded kind link_engine acts on: READ_REQ / WRITE_REQ, neither for a snapshot or an
      // error.
      const bool request = dut.ev_error_o == 0;
      EXPECT_EQ(dut.ev_read_o != 0, request && dut.ev_code_o == omniloc::regmap::kFrameReadReq)
          << "ev_read_o";
      EXPECT_EQ(dut.ev_write_o != 0, request && dut.ev_code_o == omniloc::regmap::kFrameWriteReq)
          << "ev_write_o";
    }
    bench.step();
    if (took) {
      ++next;
      wait = next < stream.size() ? stream[next].gap_before : 0;
    } else if (wait > 0 && !(next < stream.size() && wait == 0)) {
      --wait;
    }
    if (next >= stream.size()) ++tail;
  }
  return events;
}

TEST(FrameRx, MixedStreamMatchesGoldenParser) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 41);
  const auto stream = make_stream(seed, 3000);
  const auto expected = golden_parse(stream);
  const auto got = run(stream, seed);
  if (got != expected) {
    const auto vcd = omniloc::rtl_tb::trace_path("frame_rx", seed);
    run(stream, seed, vcd);
    ADD_FAILURE() << "trace: " << vcd;
  }
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], expected[i]) << "event " << i;
  // The mix really exercised every outcome.
  int requests = 0, crc = 0, malformed = 0, truncated = 0;
  for (const auto& e : expected) {
    if (!e.error)
      ++requests;
    else if (e.code == omniloc::regmap::kErrBadCrc)
      ++crc;
    else if (e.addr == 0xFF)
      ++truncated;
    else
      ++malformed;
  }
  std::printf("events: %d requests, %d bad CRC, %d malformed, %d truncated\n", requests, crc,
              malformed, truncated);
  EXPECT_GT(requests, 500);
  EXPECT_GT(crc, 100);
  EXPECT_GT(malformed, 100);
  EXPECT_GT(truncated, 100);
}

}  // namespace
